//! [`Group`]: an axis group of the server (`[[group]]` in its config), by handle: lines and
//! trajectories sent on the `paths` service and run by a `Run` command, feed hold, feed
//! override, cancel, stop, claims of every member axis at once; and the wait for the
//! motion this client ran to end ([`Group::wait_done`], judged frame by frame against the
//! client's last run on the group).

use core::time::Duration;
use std::rc::Rc;
use std::time::Instant;

use iceoryx2::service::Service;
use motion_ipc::{
    CommandKind, CommandReply, GroupInfo, GroupMotion, GroupPath, MAX_GROUP_AXES, MotionFrame,
    Reason, Target,
};

use crate::group_state::{GroupOutcome, GroupStatus};
use crate::ports::{self, Opening, PathPorts};
use crate::{
    Accepted, Axis, ClaimGuard, Client, ClientError, ConnectError, Frame, GroupRefusal, Trajectory,
    TrajectoryError,
};

/// The last path a client ran on a group: which motion its waits are about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct RunMark {
    /// The path's id.
    pub(crate) path_id: u64,
    /// The tick the server accepted the `Run` in.
    pub(crate) tick: u64,
    /// The client's restart count then.
    pub(crate) epoch: u64,
}

/// A path the server accepted and runs: its id (echoed in the frames'
/// [`GroupState::path_id`](motion_ipc::GroupState::path_id)) and the tick it started in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GroupRun {
    /// The id this client gave the path.
    pub path_id: u64,
    /// The tick in which the server accepted the `Run`.
    pub tick: u64,
    /// The `Run` request's sequence number.
    pub sequence: u64,
}

/// One axis group of the server, found by name with [`Client::group`]. Cheap to copy.
///
/// Positions, velocities and accelerations are given per member axis in the group's order
/// ([`Group::axes`]), in each axis's unit. Every motion command is judged by the server and
/// answered; a refused path names its point and axis ([`ClientError::GroupRefused`]).
///
/// ```no_run
/// use core::time::Duration;
/// use iceoryx2::prelude::ipc;
/// use motion_client::{Client, ClientError, Trajectory};
///
/// let client = Client::<ipc::Service>::connect("demo")?;
/// let gantry = client.group("gantry")?; // targets in its order: x, feeder, lift
/// gantry.move_to(&[200.0, 100.0, 150.0])?; // one synchronized line
/// gantry.wait_done(Duration::from_secs(30))?;
///
/// let arm = client.group("arm")?; // x y z a b c
/// let mut path = Trajectory::new(arm.axes().len());
/// path.push(1.0, &[20.0, 15.0, -10.0, 30.0, 10.0, -30.0])?
///     .push(2.0, &[40.0, 30.0, -20.0, 60.0, 20.0, -60.0])?;
/// let _claim = arm.claim()?; // every axis of the arm; released on drop
/// arm.follow(&path)?;
/// arm.set_feed(0.5)?; // half speed along the path
/// match arm.wait_done(Duration::from_secs(30)) {
///     Ok(outcome) => println!("done in tick {}", outcome.tick),
///     Err(ClientError::GroupAborted(abort)) => println!("{abort}"), // reason, axis, figures
///     Err(other) => return Err(other.into()),
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct Group<'c, S: Service> {
    client: &'c Client<S>,
    index: u32,
}

impl<S: Service> Clone for Group<'_, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S: Service> Copy for Group<'_, S> {}

impl<S: Service> Client<S> {
    /// The handle of the group called `name`. [`ClientError::UnknownGroup`] lists the
    /// groups the server has; a client connected through a bridge gets
    /// [`ClientError::LocalOnly`] (groups need shared memory for now).
    pub fn group(&self, name: &str) -> Result<Group<'_, S>, ClientError> {
        if self.is_remote() {
            return Err(ClientError::LocalOnly { what: "groups" });
        }
        let info = self.info()?;
        let index = info
            .group_index(name)
            .ok_or_else(|| ClientError::UnknownGroup {
                name: name.to_owned(),
                known: info.groups().iter().map(|g| g.name().to_owned()).collect(),
            })?;
        Ok(Group {
            client: self,
            index: u32::try_from(index).unwrap_or(u32::MAX),
        })
    }

    /// Handles of every group, in config order (none through a bridge).
    pub fn groups(&self) -> Vec<Group<'_, S>> {
        if self.is_remote() {
            return Vec::new();
        }
        let count = self.info.current().map_or(0, |info| info.groups().len());
        (0..count)
            .map(|index| Group {
                client: self,
                index: u32::try_from(index).unwrap_or(u32::MAX),
            })
            .collect()
    }

    /// The static description of group `index` (a copy).
    pub(crate) fn group_info(&self, index: usize) -> GroupInfo {
        self.info
            .current()
            .and_then(|info| info.groups().get(index).copied())
            .unwrap_or(GroupInfo::EMPTY)
    }

    /// The name of axis `index`, `#index` when the description has none.
    pub(crate) fn axis_name(&self, index: u32) -> String {
        let info = self.axis_info(index as usize);
        match info.name() {
            "" => format!("#{index}"),
            name => name.to_owned(),
        }
    }

    /// A refused group command as [`ClientError::GroupRefused`], with the axis named.
    pub(crate) fn group_refusal(&self, reply: &CommandReply, reason: Reason) -> ClientError {
        let axis_index = (reply.at_axis != u32::MAX).then_some(reply.at_axis);
        let point = (reply.at_point != u32::MAX).then_some(reply.at_point);
        let figures = reply.value != 0.0 || reply.limit != 0.0 || point.is_some();
        let figures = figures && reason != Reason::ClaimedByOther;
        ClientError::GroupRefused(Box::new(GroupRefusal {
            kind: CommandKind::try_from(reply.kind).map_or("command", CommandKind::name),
            group: self.group_name(reply.axis),
            reason,
            tick: reply.tick_applied,
            point,
            axis: axis_index.map(|index| self.axis_name(index)),
            axis_index,
            unit: axis_index
                .map(|index| self.axis_info(index as usize).unit().to_owned())
                .unwrap_or_default(),
            holder: (!reply.holder.is_none()).then_some(reply.holder),
            value: figures.then_some(reply.value),
            limit: figures.then_some(reply.limit),
        }))
    }

    /// The name of group `index`, `#index` when the description has none.
    pub(crate) fn group_name(&self, index: u32) -> String {
        match self.group_info(index as usize).name() {
            "" => format!("#{index}"),
            name => name.to_owned(),
        }
    }

    fn next_path_id(&self) -> u64 {
        let id = self.path_ids.get().wrapping_add(1).max(1);
        self.path_ids.set(id);
        id
    }

    pub(crate) fn run_mark(&self, group: u32) -> Option<RunMark> {
        self.group_runs
            .borrow()
            .get(group as usize)
            .copied()
            .flatten()
    }

    fn note_run(&self, group: u32, path_id: u64, tick: u64) {
        let mut runs = self.group_runs.borrow_mut();
        let index = group as usize;
        if runs.len() <= index {
            runs.resize(index + 1, None);
        }
        runs[index] = Some(RunMark {
            path_id,
            tick,
            epoch: self.session.epoch(),
        });
    }

    /// The publisher on `paths`, created on first use.
    fn path_ports(&self, group: &str) -> Result<Rc<PathPorts<S>>, ClientError> {
        if let Some(ports) = self.paths.borrow().as_ref() {
            return Ok(Rc::clone(ports));
        }
        let service = self.names.paths();
        let opening = Opening::new(&self.server, self.connect_timeout);
        let ports = ports::open_paths(&self.node, &opening, &service).map_err(|error| match error {
            ConnectError::NoServer { .. } => ClientError::PathNotSent {
                group: group.to_owned(),
                why: format!(
                    "the server offers no {service} service (a server without groups, older than \
                     motion-ipc schema 7?)"
                ),
            },
            other => other.into(),
        })?;
        let ports = Rc::new(ports);
        *self.paths.borrow_mut() = Some(Rc::clone(&ports));
        Ok(ports)
    }

    /// Loans a path sample, writes it with `fill` and sends it; how many subscribers got it.
    fn send_path(
        ports: &PathPorts<S>,
        fill: &dyn Fn(&mut GroupPath),
    ) -> Result<usize, ClientError> {
        let sample = ports
            .publisher
            .loan_uninit()
            .map_err(|error| ClientError::ipc("loan a path sample", error))?;
        // Initialised from the constant (safe code cannot leave a loaned sample
        // uninitialised), then filled in place. An optimised build writes the constant
        // straight into shared memory (measured: no more stack than connecting, 256 KB);
        // an unoptimised one passes it through about 1.2 MB of stack (iceoryx2's
        // `write_payload` takes the value), see `Group::follow`.
        let mut sample = sample.write_payload(GroupPath::EMPTY);
        fill(sample.payload_mut());
        sample
            .send()
            .map_err(|error| ClientError::ipc("send a path", error))
    }

    /// Publishes a path on `paths` for group `group`, reopening the service once if the
    /// server recreated it.
    fn publish_path(&self, group: &str, fill: &dyn Fn(&mut GroupPath)) -> Result<(), ClientError> {
        let ports = self.path_ports(group)?;
        let mut delivered = Self::send_path(&ports, fill)?;
        if delivered == 0 {
            let now = ports::pubsub_id_now::<S, GroupPath>(&self.node, &self.names.paths());
            if now.is_some_and(|id| id != ports.service_id) {
                *self.paths.borrow_mut() = None;
                drop(ports);
                let ports = self.path_ports(group)?;
                delivered = Self::send_path(&ports, fill)?;
            }
        }
        if delivered == 0 {
            return Err(ClientError::PathNotSent {
                group: group.to_owned(),
                why: format!(
                    "no server subscribes to {} (is motiond stopping, or older than schema 7?)",
                    self.names.paths()
                ),
            });
        }
        Ok(())
    }
}

impl<'c, S: Service> Group<'c, S> {
    /// The group index (config order), as used in frames and requests.
    pub fn index(&self) -> u32 {
        self.index
    }

    /// The group's static description (members, tolerances, goal time, stream keys).
    pub fn info(&self) -> GroupInfo {
        self.client.group_info(self.index as usize)
    }

    /// The group's name.
    pub fn name(&self) -> String {
        self.client.group_name(self.index)
    }

    /// The member axes' names, in the group's order (the order of every target).
    pub fn axes(&self) -> Vec<String> {
        self.info()
            .axes()
            .iter()
            .map(|&axis| self.client.axis_name(axis))
            .collect()
    }

    /// The member axes' handles, in the group's order.
    pub fn axis_handles(&self) -> Vec<Axis<'c, S>> {
        self.info()
            .axes()
            .iter()
            .map(|&axis| Axis::new(self.client, axis as usize))
            .collect()
    }

    fn command(&self, kind: CommandKind, values: [f64; 3]) -> Result<Accepted, ClientError> {
        self.client
            .command_to(Target::Group, self.index, kind, values)
    }

    fn axes_error(&self, got: usize) -> ClientError {
        let info = self.info();
        TrajectoryError::GroupAxes {
            group: self.name(),
            axes: self.axes().join(", "),
            expected: info.axes().len(),
            got,
        }
        .into()
    }

    /// A synchronized straight line in joint space to `targets` (the group's order) at the
    /// axes' full velocity and acceleration limits: every axis starts and arrives together.
    pub fn move_to(&self, targets: &[f64]) -> Result<GroupRun, ClientError> {
        self.move_to_scaled(targets, 1.0, 1.0)
    }

    /// [`Group::move_to`] with every axis's velocity and acceleration limits scaled by
    /// `velocity_scale` and `accel_scale`, each in (0, 1].
    pub fn move_to_scaled(
        &self,
        targets: &[f64],
        velocity_scale: f64,
        accel_scale: f64,
    ) -> Result<GroupRun, ClientError> {
        if targets.len() != self.info().axes().len() {
            return Err(self.axes_error(targets.len()));
        }
        if let Some((axis, value)) = targets.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(TrajectoryError::NotFinite {
                point: 0,
                axis,
                what: "position",
                value: *value,
            }
            .into());
        }
        let group = self.index;
        self.run(&|path, id| path.set_line(group, id, targets, (velocity_scale, accel_scale)))
    }

    /// Follows `trajectory` (its axes in the group's order); points with a time of 0 must
    /// be where the group is, a first point later than 0 is reached from where it is.
    ///
    /// Every path (a line too) is a ≈400 KB sample on the `paths` service, loaned from
    /// shared memory and filled in place; the publisher is created by the first path this
    /// client sends. In an unoptimised (debug) build the sample's initialisation passes
    /// through about 1.2 MB of the calling thread's stack: send paths from a thread with at
    /// least 2 MB (the main thread has 8 MB; release builds need no more than connecting).
    pub fn follow(&self, trajectory: &Trajectory) -> Result<GroupRun, ClientError> {
        if trajectory.axes() != self.info().axes().len() || trajectory.axes() > MAX_GROUP_AXES {
            return Err(self.axes_error(trajectory.axes()));
        }
        if trajectory.is_empty() {
            return Err(TrajectoryError::Empty.into());
        }
        let group = self.index;
        self.run(&|path, id| trajectory.write_into(path, group, id))
    }

    /// Publishes a path written by `write` under a new id, then runs it.
    fn run(&self, write: &dyn Fn(&mut GroupPath, u64)) -> Result<GroupRun, ClientError> {
        self.client.check_server()?;
        let id = self.client.next_path_id();
        self.client
            .publish_path(&self.name(), &|path| write(path, id))?;
        // Ids are counted up from 1: exact in an f64 far beyond any client's life.
        let accepted = self.command(CommandKind::Run, [id as f64, 0.0, 0.0])?;
        self.client.note_run(self.index, id, accepted.tick);
        Ok(GroupRun {
            path_id: id,
            tick: accepted.tick,
            sequence: accepted.sequence,
        })
    }

    /// Feed hold: brings the group to rest along its path at its axes' acceleration limits
    /// (`held` in the frames); [`Group::resume`] continues.
    pub fn hold(&self) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Hold, [0.0; 3])
    }

    /// Continues a held path at the set feed.
    pub fn resume(&self) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Resume, [0.0; 3])
    }

    /// Sets the feed override: 0.0..=1.5 (1.0 = 100 %); time along the path runs at this
    /// rate, changed within the axes' acceleration limits.
    pub fn set_feed(&self, feed: f64) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Feed, [feed, 0.0, 0.0])
    }

    /// Brings the group to rest along its path, then ends its motion (aborted, `cancelled`).
    pub fn cancel(&self) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Cancel, [0.0; 3])
    }

    /// Stops every member axis (decelerate and hold), ending a running motion (aborted,
    /// `stopped`). Sent even after an unacknowledged server restart.
    pub fn stop(&self) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Stop, [0.0; 3])
    }

    /// Claims every member axis at once (all or none) and returns a guard that releases
    /// them when dropped. A refusal names the axis already held and its holder.
    pub fn claim(&self) -> Result<ClaimGuard<'c, S>, ClientError> {
        ClaimGuard::take(self.client, Target::Group, self.index)
    }

    /// Releases every member axis's claim (all or none).
    pub fn release(&self) -> Result<Accepted, ClientError> {
        self.command(CommandKind::Release, [0.0; 3])
    }

    /// The group's state in the newest frame, typed, the abort's axis named.
    pub fn state(&self) -> Result<GroupStatus, ClientError> {
        let info = self.client.info()?;
        let frame = self.client.latest()?;
        GroupStatus::read(&info, &frame, self.index as usize)
    }

    pub(crate) fn client(&self) -> &'c Client<S> {
        self.client
    }
}

/// Ticks after a `Run` was accepted in which a frame may still show the group's previous
/// motion (a server that starts a path in the tick after accepting it).
const START_GRACE_TICKS: u64 = 2;

/// What one frame says about the wait.
enum Step {
    Wait,
    Done(GroupOutcome),
    Failed(ClientError),
}

impl<S: Service> Group<'_, S> {
    /// Waits until the motion this client last ran on the group (or, when it ran none, the
    /// motion running now) ends: `Ok` when it reached its end (`done`: every axis within its
    /// goal tolerance), [`ClientError::GroupAborted`] naming the reason, the axis and the
    /// figures when it was aborted, [`ClientError::GroupTimeout`] when `timeout` passes.
    pub fn wait_done(&self, timeout: Duration) -> Result<GroupOutcome, ClientError> {
        self.wait_done_observing(timeout, |_| {})
    }

    /// [`Group::wait_done`], calling `observe` with every frame it reads (in order; frames
    /// the client was too slow for are lost: compare ticks).
    pub fn wait_done_observing(
        &self,
        timeout: Duration,
        mut observe: impl FnMut(&MotionFrame),
    ) -> Result<GroupOutcome, ClientError> {
        let client = self.client();
        let deadline = Instant::now() + timeout;
        let mark = client.run_mark(self.index());
        let info = client.info()?;
        let mut frame: Frame<S> = client.latest()?;
        let mut motion = GroupMotion::Idle;
        loop {
            if let Some(mark) = mark
                && client.session.epoch() != mark.epoch
                && let Some(restart) = client.session.last_restart()
            {
                return Err(ClientError::ServerRestarted(restart));
            }
            if mark.is_none_or(|mark| frame.tick >= mark.tick) {
                observe(&frame);
                let status = GroupStatus::read(&info, &frame, self.index() as usize)?;
                motion = status.motion;
                match judge(client, mark, &status) {
                    Step::Wait => {}
                    Step::Done(outcome) => return Ok(outcome),
                    Step::Failed(error) => return Err(error),
                }
            }
            let now = Instant::now();
            let timed_out = || ClientError::GroupTimeout {
                group: self.name(),
                waited: timeout,
                motion: motion.name(),
            };
            if now >= deadline {
                return Err(timed_out());
            }
            drop(frame);
            frame = match client.next_frame(deadline - now) {
                Ok(next) => next,
                Err(ClientError::NoFrame(_)) => return Err(timed_out()),
                Err(error) => return Err(error),
            };
        }
    }
}

fn outcome(status: &GroupStatus) -> GroupOutcome {
    GroupOutcome {
        group: status.name.clone(),
        motion: status.motion,
        path_id: status.path_id,
        tick: status.tick,
        time: status.time,
        duration: status.duration,
    }
}

/// What `status` means for a wait about `mark` (the client's last run on the group).
fn judge<S: Service>(client: &Client<S>, mark: Option<RunMark>, status: &GroupStatus) -> Step {
    let ended = |status: &GroupStatus| match status.motion {
        GroupMotion::Done | GroupMotion::Idle => Step::Done(outcome(status)),
        GroupMotion::Aborted => Step::Failed(ClientError::GroupAborted(Box::new(status.aborted()))),
        GroupMotion::Moving | GroupMotion::Holding | GroupMotion::Held => Step::Wait,
    };
    let Some(mark) = mark else {
        return ended(status);
    };
    let theirs = status.owner.is_some_and(|owner| owner != client.id());
    if status.path_id == mark.path_id && !(theirs && status.motion.active()) {
        return match status.motion {
            GroupMotion::Idle => Step::Failed(ClientError::GroupWaitAborted {
                group: status.name.clone(),
                why: format!(
                    "it went idle without ending path {} (the server restarted it?)",
                    mark.path_id
                ),
            }),
            _ => ended(status),
        };
    }
    if status.tick <= mark.tick + START_GRACE_TICKS && !status.motion.active() {
        // The frame may not show the new path yet.
        return Step::Wait;
    }
    Step::Failed(ClientError::GroupWaitAborted {
        group: status.name.clone(),
        why: format!(
            "another motion (path {}, {}) replaced path {} that this client ran",
            status.path_id,
            status.motion.name(),
            mark.path_id
        ),
    })
}
