/*
 * motiond from C: reads frames straight from shared memory and sends commands, with
 * iceoryx2's C API and the payload definitions of include/motiond.h.
 *
 *   motiond_c_example [INSTANCE [AXIS [POSITION]]]      (defaults: demo x 25)
 *
 * 1. reads the server description (motiond/INSTANCE/info) and finds AXIS;
 * 2. reads 200 frames (motiond/INSTANCE/frame), sleeping on the tick event between them;
 * 3. sends a ramp to POSITION and, to show a refusal, a position beyond the soft limit
 *    (motiond/INSTANCE/command), printing the server's reason;
 * 4. reads frames until AXIS has arrived.
 *
 * Exit status 0 when the ramp was accepted and arrived and the second command was refused
 * as out of range. Build: see README.md beside this file.
 */
#include <stdalign.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "iox2/iceoryx2.h"
#include "motiond.h"

/* A text field as a C string (fields are zero padded, not always zero terminated). */
static void field_text(char *out, size_t out_len, const uint8_t *field, size_t field_len) {
    size_t n = 0;
    while (n < field_len && n + 1 < out_len && field[n] != 0) {
        out[n] = (char) field[n];
        n++;
    }
    out[n] = '\0';
}

static iox2_service_name_h make_service_name(const char *format, const char *instance) {
    char name[256];
    snprintf(name, sizeof(name), format, instance);
    iox2_service_name_h handle = NULL;
    if (iox2_service_name_new(NULL, name, strlen(name), &handle) != IOX2_OK) {
        fprintf(stderr, "invalid service name %s\n", name);
        return NULL;
    }
    return handle;
}

/* Opens (never creates) a publish-subscribe service of motiond and subscribes to it. */
static int subscribe(iox2_node_h *node, const char *format, const char *instance, const char *type_name,
                     size_t size, size_t align, iox2_port_factory_pub_sub_h *service, iox2_subscriber_h *subscriber) {
    iox2_service_name_h name = make_service_name(format, instance);
    if (name == NULL) {
        return -1;
    }
    iox2_service_builder_h builder = iox2_node_service_builder(node, NULL, iox2_cast_service_name_ptr(name));
    iox2_service_builder_pub_sub_h pub_sub = iox2_service_builder_pub_sub(builder);
    int rc = iox2_service_builder_pub_sub_set_payload_type_details(
        &pub_sub, iox2_type_variant_e_FIXED_SIZE, type_name, strlen(type_name), size, align);
    if (rc == IOX2_OK) {
        rc = iox2_service_builder_pub_sub_open(pub_sub, NULL, service);
    }
    iox2_service_name_drop(name);
    if (rc != IOX2_OK) {
        fprintf(stderr,
                "cannot open ");
        fprintf(stderr, format, instance);
        fprintf(stderr, " (error %d): is motiond running with [server] name = \"%s\"?\n", rc, instance);
        return rc;
    }
    iox2_port_factory_subscriber_builder_h sub_builder = iox2_port_factory_pub_sub_subscriber_builder(service, NULL);
    rc = iox2_port_factory_subscriber_builder_create(sub_builder, NULL, subscriber);
    if (rc != IOX2_OK) {
        fprintf(stderr, "cannot subscribe (error %d)\n", rc);
    }
    return rc;
}

static void ignore_event(const iox2_event_id_t *id, uint64_t count, iox2_callback_context ctx) {
    (void) id;
    (void) count;
    (void) ctx;
}

/* Sends one request and waits up to a second for its reply. */
static int command(iox2_node_h *node, iox2_client_h *client, const motiond_command_request_t *request,
                   motiond_command_reply_t *reply) {
    iox2_pending_response_h pending = NULL;
    int rc = iox2_client_send_copy(client, request, sizeof(*request), 1, NULL, &pending);
    if (rc != IOX2_OK) {
        fprintf(stderr, "cannot send the command (error %d)\n", rc);
        return rc;
    }
    if (iox2_pending_response_number_of_server_connections(&pending) == 0) {
        fprintf(stderr, "no motiond serves the command service\n");
        iox2_pending_response_drop(pending);
        return -1;
    }
    for (int attempt = 0; attempt < 1000; attempt++) {
        iox2_response_h response = NULL;
        rc = iox2_pending_response_receive(&pending, NULL, &response);
        if (rc != IOX2_OK) {
            break;
        }
        if (response != NULL) {
            const void *payload = NULL;
            iox2_response_payload(&response, &payload, NULL);
            memcpy(reply, payload, sizeof(*reply));
            iox2_response_drop(response);
            if (reply->sequence == request->sequence) {
                iox2_pending_response_drop(pending);
                return IOX2_OK;
            }
            continue;
        }
        if (iox2_node_wait(node, 0, 1000000) != IOX2_OK) {
            break; /* Ctrl-C */
        }
    }
    iox2_pending_response_drop(pending);
    fprintf(stderr, "no reply from the server\n");
    return -1;
}

static void print_reply(const motiond_command_reply_t *reply) {
    if (reply->reason == MOTIOND_REASON_ACCEPTED) {
        printf("accepted at tick %llu\n", (unsigned long long) reply->tick_applied);
    } else {
        const char *text = motiond_reason_text(reply->reason);
        printf("refused: %s\n", text != NULL ? text : "unknown reason");
    }
}

int main(int argc, char **argv) {
    const char *instance = argc > 1 ? argv[1] : "demo";
    const char *axis_name = argc > 2 ? argv[2] : "x";
    double goal = argc > 3 ? strtod(argv[3], NULL) : 25.0;
    int status = 1;

    iox2_set_log_level_from_env_or(iox2_log_level_e_ERROR);
    iox2_node_builder_h node_builder = iox2_node_builder_new(NULL);
    iox2_node_h node = NULL;
    if (iox2_node_builder_create(node_builder, NULL, iox2_service_type_e_IPC, &node) != IOX2_OK) {
        fprintf(stderr, "cannot create an iceoryx2 node\n");
        return 1;
    }

    /* 1. The server description: tick rate, axes, their limits. */
    iox2_port_factory_pub_sub_h info_service = NULL;
    iox2_subscriber_h info_subscriber = NULL;
    if (subscribe(&node, MOTIOND_SERVICE_INFO, instance, MOTIOND_TYPE_NAME_SERVER_INFO,
                  sizeof(motiond_server_info_t), alignof(motiond_server_info_t), &info_service,
                  &info_subscriber) != IOX2_OK) {
        goto drop_node;
    }
    uint32_t axis = UINT32_MAX;
    uint32_t tick_hz = 1000;
    double axis_max = 0.0;
    char unit[MOTIOND_UNIT_LEN + 1] = "";
    for (int attempt = 0; attempt < 200 && axis == UINT32_MAX; attempt++) {
        iox2_sample_h sample = NULL;
        if (iox2_subscriber_receive(&info_subscriber, NULL, &sample) == IOX2_OK && sample != NULL) {
            const motiond_server_info_t *info = NULL;
            iox2_sample_payload(&sample, (const void **) &info, NULL);
            if (info->schema_version != MOTIOND_SCHEMA_VERSION) {
                fprintf(stderr, "the server speaks schema %u, this program %u\n", info->schema_version,
                        MOTIOND_SCHEMA_VERSION);
                iox2_sample_drop(sample);
                goto drop_info;
            }
            printf("motiond \"%s\": %u axes at %u Hz\n", instance, info->axis_count, info->tick_hz);
            tick_hz = info->tick_hz;
            for (uint32_t i = 0; i < info->axis_count && i < MOTIOND_MAX_AXES; i++) {
                char name[MOTIOND_NAME_LEN + 1];
                field_text(name, sizeof(name), info->axes[i].name, MOTIOND_NAME_LEN);
                if (strcmp(name, axis_name) == 0) {
                    axis = i;
                    axis_max = info->axes[i].max;
                    field_text(unit, sizeof(unit), info->axes[i].unit, MOTIOND_UNIT_LEN);
                }
            }
            iox2_sample_drop(sample);
            if (axis == UINT32_MAX) {
                fprintf(stderr, "no axis named %s\n", axis_name);
                goto drop_info;
            }
        } else if (iox2_node_wait(&node, 0, 10000000) != IOX2_OK) {
            goto drop_info;
        }
    }
    if (axis == UINT32_MAX) {
        fprintf(stderr, "no server description received\n");
        goto drop_info;
    }

    /* 2. Frames, in order, woken by the tick event. */
    iox2_port_factory_pub_sub_h frame_service = NULL;
    iox2_subscriber_h frames = NULL;
    if (subscribe(&node, MOTIOND_SERVICE_FRAME, instance, MOTIOND_TYPE_NAME_MOTION_FRAME,
                  sizeof(motiond_motion_frame_t), alignof(motiond_motion_frame_t), &frame_service,
                  &frames) != IOX2_OK) {
        goto drop_info;
    }
    iox2_service_name_h tick_name = make_service_name(MOTIOND_SERVICE_TICK, instance);
    iox2_service_builder_h tick_builder = iox2_node_service_builder(&node, NULL, iox2_cast_service_name_ptr(tick_name));
    iox2_port_factory_event_h tick_service = NULL;
    int rc = iox2_service_builder_event_open(iox2_service_builder_event(tick_builder), NULL, &tick_service);
    iox2_service_name_drop(tick_name);
    if (rc != IOX2_OK) {
        fprintf(stderr, "cannot open the tick event (error %d)\n", rc);
        goto drop_frames;
    }
    iox2_listener_h tick = NULL;
    if (iox2_port_factory_listener_builder_create(iox2_port_factory_event_listener_builder(&tick_service, NULL),
                                                  NULL, &tick) != IOX2_OK) {
        fprintf(stderr, "cannot listen to the tick event\n");
        goto drop_tick_service;
    }

    uint64_t first_tick = 0;
    uint64_t last_tick = 0;
    uint64_t gaps = 0;
    int read = 0;
    while (read < 200) {
        uint64_t notifications = 0;
        if (iox2_listener_timed_wait(&tick, &notifications, ignore_event, NULL, 0, 100000000) != IOX2_OK) {
            goto drop_tick;
        }
        iox2_sample_h sample = NULL;
        while (read < 200 && iox2_subscriber_receive(&frames, NULL, &sample) == IOX2_OK && sample != NULL) {
            const motiond_motion_frame_t *frame = NULL;
            iox2_sample_payload(&sample, (const void **) &frame, NULL);
            if (read == 0) {
                first_tick = frame->tick;
            } else if (frame->tick != last_tick + 1) {
                gaps++;
            }
            last_tick = frame->tick;
            if (read % 50 == 0) {
                const motiond_axis_state_t *state = &frame->axes[axis];
                printf("tick %llu  %s %.3f %s  v %.3f  mode %u  %s\n", (unsigned long long) frame->tick, axis_name,
                       state->position, unit, state->velocity, state->mode,
                       motiond_device_state_text(state->device_state));
            }
            read++;
            iox2_sample_drop(sample);
            sample = NULL;
        }
    }
    printf("read %d frames, ticks %llu..%llu, %llu gaps (ticks the server skipped)\n", read,
           (unsigned long long) first_tick, (unsigned long long) last_tick, (unsigned long long) gaps);

    /* 3. Commands: a ramp, then a position beyond the soft limit. */
    iox2_service_name_h command_name = make_service_name(MOTIOND_SERVICE_COMMAND, instance);
    iox2_service_builder_h command_builder =
        iox2_node_service_builder(&node, NULL, iox2_cast_service_name_ptr(command_name));
    iox2_service_builder_request_response_h request_response = iox2_service_builder_request_response(command_builder);
    iox2_service_builder_request_response_set_request_payload_type_details(
        &request_response, iox2_type_variant_e_FIXED_SIZE, MOTIOND_TYPE_NAME_COMMAND_REQUEST,
        strlen(MOTIOND_TYPE_NAME_COMMAND_REQUEST), sizeof(motiond_command_request_t),
        alignof(motiond_command_request_t));
    iox2_service_builder_request_response_set_response_payload_type_details(
        &request_response, iox2_type_variant_e_FIXED_SIZE, MOTIOND_TYPE_NAME_COMMAND_REPLY,
        strlen(MOTIOND_TYPE_NAME_COMMAND_REPLY), sizeof(motiond_command_reply_t), alignof(motiond_command_reply_t));
    iox2_port_factory_request_response_h command_service = NULL;
    rc = iox2_service_builder_request_response_open(request_response, NULL, &command_service);
    iox2_service_name_drop(command_name);
    if (rc != IOX2_OK) {
        fprintf(stderr, "cannot open the command service (error %d)\n", rc);
        goto drop_tick;
    }
    iox2_client_h client = NULL;
    if (iox2_port_factory_client_builder_create(iox2_port_factory_request_response_client_builder(&command_service, NULL),
                                                NULL, &client) != IOX2_OK) {
        fprintf(stderr, "cannot create a command client\n");
        goto drop_command_service;
    }

    /* client stays zero: "the sender"; the server knows which node sent the request. */
    motiond_command_request_t ramp = motiond_command_request(MOTIOND_COMMAND_KIND_RAMP_POSITION, axis, 1);
    ramp.values[0] = goal; /* values[1], values[2] = 0: the axis's max velocity and accel */
    motiond_command_reply_t ramp_reply;
    if (command(&node, &client, &ramp, &ramp_reply) != IOX2_OK) {
        goto drop_client;
    }
    printf("ramp %s to %.3f %s: ", axis_name, goal, unit);
    print_reply(&ramp_reply);

    motiond_command_request_t beyond = motiond_command_request(MOTIOND_COMMAND_KIND_POSITION, axis, 2);
    beyond.values[0] = axis_max + 1000.0;
    motiond_command_reply_t beyond_reply;
    if (command(&node, &client, &beyond, &beyond_reply) != IOX2_OK) {
        goto drop_client;
    }
    printf("position %s %.3f %s: ", axis_name, beyond.values[0], unit);
    print_reply(&beyond_reply);

    /* 4. Until the axis has arrived (flags from a frame at or after the ramp's tick), for
     *    at most 30 s of ticks or 5 s without any tick. */
    bool arrived = false;
    uint64_t deadline_tick = ramp_reply.tick_applied + 30ull * tick_hz;
    int silent = 0;
    while (ramp_reply.reason == MOTIOND_REASON_ACCEPTED && !arrived && last_tick < deadline_tick && silent < 50) {
        uint64_t notifications = 0;
        if (iox2_listener_timed_wait(&tick, &notifications, ignore_event, NULL, 0, 100000000) != IOX2_OK) {
            break;
        }
        silent = notifications == 0 ? silent + 1 : 0;
        iox2_sample_h sample = NULL;
        while (iox2_subscriber_receive(&frames, NULL, &sample) == IOX2_OK && sample != NULL) {
            const motiond_motion_frame_t *frame = NULL;
            iox2_sample_payload(&sample, (const void **) &frame, NULL);
            const motiond_axis_state_t *state = &frame->axes[axis];
            last_tick = frame->tick;
            if (!arrived && frame->tick >= ramp_reply.tick_applied && (state->flags & MOTIOND_AXIS_FLAGS_ARRIVED) != 0
                && (state->flags & MOTIOND_AXIS_FLAGS_MOVING) == 0) {
                printf("arrived at %.3f %s at tick %llu\n", state->position, unit, (unsigned long long) frame->tick);
                arrived = true;
            }
            iox2_sample_drop(sample);
            sample = NULL;
        }
    }
    if (arrived && beyond_reply.reason == MOTIOND_REASON_OUT_OF_RANGE) {
        status = 0;
    }

drop_client:
    iox2_client_drop(client);
drop_command_service:
    iox2_port_factory_request_response_drop(command_service);
drop_tick:
    iox2_listener_drop(tick);
drop_tick_service:
    iox2_port_factory_event_drop(tick_service);
drop_frames:
    iox2_subscriber_drop(frames);
    iox2_port_factory_pub_sub_drop(frame_service);
drop_info:
    iox2_subscriber_drop(info_subscriber);
    iox2_port_factory_pub_sub_drop(info_service);
drop_node:
    iox2_node_drop(node);
    return status;
}
