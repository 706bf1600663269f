//! The `registry!` macro: from the one list of boards, [`BOARDS`](crate::BOARDS) and
//! [`AnyDriver`](crate::AnyDriver), whose `impl Driver` hands every call to the board's own
//! driver with a `match` (static dispatch: the tick calls no virtual method and the
//! drivers live inline in the links' buses).

/// Declares the registry: `Variant => board_crate::BoardType,` per board.
macro_rules! registry {
    ($(#[$doc:meta])* $($variant:ident => $board:path),+ $(,)?) => {
        $(#[$doc])*
        pub static BOARDS: &[&dyn Board] = &[$(&$board),+];

        /// The driver of any registered board: one variant per board, holding the board's
        /// own driver type (`TypedBoard::Driver`).
        // The variants differ in size (a driver's fixed buffers: no allocation after
        // start-up); each lives once in its link's bus, built once, never moved per tick,
        // so the size of the largest costs a few kilobytes per device and nothing per tick.
        #[allow(clippy::large_enum_variant)]
        #[derive(serde::Serialize, serde::Deserialize, Debug)]
        pub enum AnyDriver {
            $(
                #[allow(missing_docs)]
                $variant(<$board as TypedBoard>::Driver),
            )+
        }

        impl AnyDriver {
            /// The driver of the device `spec` describes, built by its board.
            ///
            /// # Errors
            /// A value of the spec the board refuses.
            ///
            /// # Panics
            /// For a model outside the registry (a programming error: every model the
            /// server sees came from the registry).
            pub fn build(spec: &DriverSpec) -> Result<Self, SpecError> {
                $(
                    if Board::model(&$board) == spec.model {
                        return TypedBoard::driver(&$board, spec).map(Self::$variant);
                    }
                )+
                panic!("board {} is not in the registry (motion_boards::BOARDS)", spec.model)
            }
        }

        macro_rules! each_driver {
            ($self:expr, $driver:ident => $call:expr) => {
                match $self {
                    $(AnyDriver::$variant($driver) => $call,)+
                }
            };
        }

        impl motion_drivers::Driver for AnyDriver {
            fn model(&self) -> Model {
                each_driver!(self, d => d.model())
            }
            fn channel_count(&self) -> usize {
                each_driver!(self, d => d.channel_count())
            }
            fn capabilities(&self, channel: usize) -> motion_drivers::GoalKinds {
                each_driver!(self, d => d.capabilities(channel))
            }
            fn rate_floor(&self, channel: usize) -> motion_drivers::RateFloor {
                each_driver!(self, d => d.rate_floor(channel))
            }
            fn follow(&self, channel: usize) -> motion_drivers::Follow {
                each_driver!(self, d => d.follow(channel))
            }
            fn refresh_budget(&self) -> core::time::Duration {
                each_driver!(self, d => d.refresh_budget())
            }
            fn lead_line(
                &mut self,
                now: core::time::Duration,
                legs: &[motion_drivers::LineLeg],
            ) -> Result<bool, motion_drivers::GoalError> {
                each_driver!(self, d => d.lead_line(now, legs))
            }
            fn line_ready(&self) -> bool {
                each_driver!(self, d => d.line_ready())
            }
            fn start_line(&mut self, now: core::time::Duration) {
                each_driver!(self, d => d.start_line(now))
            }
            fn line_starting(&self) -> bool {
                each_driver!(self, d => d.line_starting())
            }
            fn pause_line(
                &mut self,
                now: core::time::Duration,
                channel: usize,
            ) -> Result<bool, motion_drivers::GoalError> {
                each_driver!(self, d => d.pause_line(now, channel))
            }
            fn resume_line(
                &mut self,
                now: core::time::Duration,
                channel: usize,
            ) -> Result<bool, motion_drivers::GoalError> {
                each_driver!(self, d => d.resume_line(now, channel))
            }
            fn handle_rx(&mut self, now: core::time::Duration, bytes: &[u8]) {
                each_driver!(self, d => d.handle_rx(now, bytes))
            }
            fn handle_timeout(&mut self, now: core::time::Duration) {
                each_driver!(self, d => d.handle_timeout(now))
            }
            fn handle_written(&mut self, at: core::time::Duration) {
                each_driver!(self, d => d.handle_written(at))
            }
            fn handle_heard(&mut self, until: core::time::Duration) {
                each_driver!(self, d => d.handle_heard(until))
            }
            fn late_answers(&self) -> &[motion_drivers::LateAnswer] {
                each_driver!(self, d => d.late_answers())
            }
            fn handle_late_answers(&mut self, others: &[motion_drivers::LateAnswer]) {
                each_driver!(self, d => d.handle_late_answers(others))
            }
            fn poll_timeout(&self) -> Option<core::time::Duration> {
                each_driver!(self, d => d.poll_timeout())
            }
            fn wants_transmit(
                &self,
                now: core::time::Duration,
            ) -> Option<motion_drivers::Priority> {
                each_driver!(self, d => d.wants_transmit(now))
            }
            fn poll_transmit(
                &mut self,
                now: core::time::Duration,
                buf: &mut [u8],
            ) -> Option<motion_drivers::Transmit> {
                each_driver!(self, d => d.poll_transmit(now, buf))
            }
            fn awaiting_reply(&self) -> bool {
                each_driver!(self, d => d.awaiting_reply())
            }
            fn goals_pending(&self) -> bool {
                each_driver!(self, d => d.goals_pending())
            }
            fn set_goal(
                &mut self,
                now: core::time::Duration,
                channel: usize,
                goal: motion_drivers::Goal,
            ) -> Result<(), motion_drivers::GoalError> {
                each_driver!(self, d => d.set_goal(now, channel, goal))
            }
            fn channel(&self, channel: usize) -> motion_drivers::ChannelState {
                each_driver!(self, d => d.channel(channel))
            }
            fn status(&self) -> motion_drivers::DeviceStatus {
                each_driver!(self, d => d.status())
            }
            fn link_down(&mut self, now: core::time::Duration) {
                each_driver!(self, d => d.link_down(now))
            }
            fn link_up(&mut self, now: core::time::Duration) {
                each_driver!(self, d => d.link_up(now))
            }
            fn read_pin(&self, pin: motion_drivers::Pin) -> Option<motion_drivers::PinReading> {
                each_driver!(self, d => d.read_pin(pin))
            }
            fn set_output(
                &mut self,
                now: core::time::Duration,
                pin: motion_drivers::Pin,
                high: bool,
            ) -> Result<(), motion_drivers::GoalError> {
                each_driver!(self, d => d.set_output(now, pin, high))
            }
            fn set_pin_value(
                &mut self,
                now: core::time::Duration,
                pin: motion_drivers::Pin,
                value: f64,
            ) -> Result<(), motion_drivers::GoalError> {
                each_driver!(self, d => d.set_pin_value(now, pin, value))
            }
            fn line_rate(&self) -> Option<u32> {
                each_driver!(self, d => d.line_rate())
            }
            fn commission(
                &mut self,
                now: core::time::Duration,
                change: motion_drivers::Commission,
            ) -> Result<(), motion_drivers::CommissionError> {
                each_driver!(self, d => d.commission(now, change))
            }
            fn keeps_references(&self) -> bool {
                each_driver!(self, d => d.keeps_references())
            }
            fn restore_references(&mut self, saved: &[motion_drivers::SavedReference]) {
                each_driver!(self, d => d.restore_references(saved))
            }
        }
    };
}
