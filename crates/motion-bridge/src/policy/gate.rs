//! What the bridge decides about stop and e-stop where a query arrives (on zenoh's thread),
//! before it waits anywhere a flood could fill: the allow-list, and for stops their own
//! rate.
//!
//! An e-stop the identity may send goes on its own path, never refused for room or rate:
//! one e-stop latches every axis, so however many arrive, the bridge forwards them as one
//! (the loop batches them) and an e-stop flood costs the server one request per round trip.
//! A stop is held to its `[[remote]]` entry's `rate` above the entry's `stop_burst` (a
//! bucket of its own per entry, apart from the bucket of other commands: a remote that
//! spent its requests on goals may still stop), so that a stop flood is refused here,
//! cheaply, and never fills the queues an e-stop or another remote's command waits in.

use core::time::Duration;
use std::collections::HashMap;

use motion_ipc::{CommandKind, CommandRequest, SCHEMA_VERSION};

use super::{Bucket, RemoteRule, no_rule, not_allowed, rule_of};
use motion_wire::keys::Refusal;

/// Where a command goes, decided where it arrives.
#[derive(Debug, Clone, PartialEq)]
pub enum Early {
    /// An e-stop this identity may send: to the e-stop's own path.
    EStop,
    /// A stop within its entry's stop rate: on to the bridge's loop.
    Stop,
    /// Refused where it arrived, with a message.
    Refuse(Refusal, String),
    /// Any other command (or a request the loop answers: another schema, an unknown kind):
    /// on to the bridge's loop, which judges it.
    Loop,
}

/// The allow-lists and the stop buckets of every `[[remote]]` entry.
#[derive(Debug)]
pub struct Gate {
    rules: Vec<RemoteRule>,
    /// Per entry (its `identity`, `*` for the wildcard): the stops' bucket.
    stops: HashMap<String, Bucket>,
}

impl Gate {
    /// The gate of `rules`.
    pub fn new(rules: Vec<RemoteRule>) -> Self {
        Self {
            rules,
            stops: HashMap::new(),
        }
    }

    /// Where `request`, sent under `identity` and arrived at `now` (the bridge's monotonic
    /// clock), goes.
    pub fn judge(&mut self, now: Duration, identity: &str, request: &CommandRequest) -> Early {
        if request.schema_version != SCHEMA_VERSION {
            return Early::Loop;
        }
        let kind = match request.kind() {
            Ok(kind @ (CommandKind::Stop | CommandKind::EStop)) => kind,
            _ => return Early::Loop,
        };
        let Some(rule) = rule_of(&self.rules, identity) else {
            let (refusal, text) = no_rule(identity);
            return Early::Refuse(refusal, text);
        };
        if !rule.allow.contains(kind) {
            let (refusal, text) = not_allowed(kind, identity, rule);
            return Early::Refuse(refusal, text);
        }
        if kind == CommandKind::EStop {
            return Early::EStop;
        }
        let (rate, burst) = (rule.rate, rule.stop_burst);
        let bucket = self.stops.entry(rule.identity.clone()).or_insert(Bucket {
            tokens: burst,
            refilled: now,
        });
        if bucket.take(now, rate, burst) {
            return Early::Stop;
        }
        let whose = if rule.identity == identity {
            format!("remote `{identity}`")
        } else {
            format!(
                "the identities under `{}` (here `{identity}`) together",
                rule.identity
            )
        };
        Early::Refuse(
            Refusal::RateLimited,
            format!(
                "{whose} sent more than {rate} stops/s (stop_burst {burst}); an e-stop is never \
                 held back"
            ),
        )
    }
}

#[cfg(test)]
mod tests {
    use motion_ipc::ClientId;

    use super::*;
    use crate::policy::KindSet;

    fn rule(identity: &str, allow: &[&str], rate: f64, stop_burst: f64) -> RemoteRule {
        RemoteRule {
            identity: identity.to_owned(),
            allow: allow.iter().fold(KindSet::NONE, |set, name| {
                set.union(KindSet::from_name(name).expect("known name"))
            }),
            rate,
            burst: 1.0,
            stop_burst,
            sessions: 1,
        }
    }

    fn request(kind: CommandKind) -> CommandRequest {
        CommandRequest::new(ClientId::NONE, 1, 0, kind)
    }

    fn ms(ms: u64) -> Duration {
        Duration::from_millis(ms)
    }

    #[test]
    fn an_estop_is_never_held_to_a_rate_and_a_stop_is_held_to_its_entrys() {
        let mut gate = Gate::new(vec![
            rule("panel", &["all"], 10.0, 5.0),
            rule("*", &["stop"], 10.0, 3.0),
        ]);
        let stop = request(CommandKind::Stop);
        let estop = request(CommandKind::EStop);
        // A thousand e-stops at once: every one takes the e-stop's path.
        for _ in 0..1000 {
            assert_eq!(gate.judge(ms(0), "panel", &estop), Early::EStop);
        }
        // The panel's stops: its stop_burst, then refused until the rate refills.
        for _ in 0..5 {
            assert_eq!(gate.judge(ms(0), "panel", &stop), Early::Stop);
        }
        match gate.judge(ms(0), "panel", &stop) {
            Early::Refuse(Refusal::RateLimited, text) => {
                assert!(
                    text.contains("remote `panel`") && text.contains("10 stops/s"),
                    "{text}"
                );
            }
            other => panic!("a stop above the burst: {other:?}"),
        }
        // 100 ms at 10/s: one more.
        assert_eq!(gate.judge(ms(100), "panel", &stop), Early::Stop);
        assert!(matches!(
            gate.judge(ms(100), "panel", &stop),
            Early::Refuse(Refusal::RateLimited, _)
        ));
        // Made-up identities under `*` share the wildcard's stop bucket; its e-stop is not
        // on its list.
        for n in 0..3 {
            assert_eq!(gate.judge(ms(0), &format!("anon-{n}"), &stop), Early::Stop);
        }
        match gate.judge(ms(0), "anon-9", &stop) {
            Early::Refuse(Refusal::RateLimited, text) => {
                assert!(text.contains("under `*` (here `anon-9`)"), "{text}");
            }
            other => panic!("the wildcard's fourth stop: {other:?}"),
        }
        match gate.judge(ms(0), "anon-9", &estop) {
            Early::Refuse(Refusal::NotAllowed, text) => {
                assert!(text.contains("`e-stop` is not allowed"), "{text}");
            }
            other => panic!("an e-stop the wildcard may not send: {other:?}"),
        }
        // The panel's own bucket is untouched by the wildcard's flood.
        assert_eq!(gate.judge(ms(1000), "panel", &stop), Early::Stop);
    }

    #[test]
    fn other_commands_and_unknown_identities() {
        let mut gate = Gate::new(vec![rule("panel", &["all"], 10.0, 5.0)]);
        assert_eq!(
            gate.judge(ms(0), "panel", &request(CommandKind::Velocity)),
            Early::Loop
        );
        let mut old = request(CommandKind::EStop);
        old.schema_version = SCHEMA_VERSION + 1;
        assert_eq!(gate.judge(ms(0), "panel", &old), Early::Loop);
        let mut unknown = request(CommandKind::Stop);
        unknown.kind = 999;
        assert_eq!(gate.judge(ms(0), "panel", &unknown), Early::Loop);
        assert!(matches!(
            gate.judge(ms(0), "stranger", &request(CommandKind::EStop)),
            Early::Refuse(Refusal::NotAllowed, _)
        ));
    }
}
