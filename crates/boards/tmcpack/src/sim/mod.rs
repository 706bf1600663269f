//! Simulated Trinamic SIXpack / QUADpack on an RS-232 / RS-485 line.
//!
//! [`TmcpackSim`] behaves like the pack's firmware on the wire, built on the `tmcpack`
//! codec: it assembles 9-byte words with the manual's packet timeout (6.1, $41), acts only
//! on words that start with its address (so on a shared RS-485 pair it stays in step with,
//! and ignores, the other packs' replies), answers queries after the transmitter switch-over
//! delay ($40, 6 ms by default), and runs six (or four) motors at the firmware's 500 Hz:
//! trapezoidal ramps with vstart / vmax / amax (8.3, 8.4), on-the-fly targets, rotation, the
//! PI controller, parallel start ($29), synchronous stop ($2A), $50 interpolation, the
//! delayed $28 answer, reference search with a simulated switch, nulloffset / testnullrange
//! checks, analogue stop limits, analogue inputs, the ready output, unit information,
//! power-down, hardware reset and baud-rate change.
//!
//! Our readings where the manual is silent (see also the `tmcpack` crate docs):
//!
//! - **one request in flight** (7.1 "Requests must not be interlaced"): the firmware has one
//!   answer buffer. A request that arrives while an answer still waits for its switch-over
//!   delay is executed, and its answer *replaces* the waiting one (the first answer is
//!   lost); bytes that arrive while the pack drives the pair (its reply plus the hold time
//!   after it) are lost, since the half-duplex receiver is off. A delayed $28 answer has
//!   its own slot and may be outstanding in parallel, as the manual allows.
//! - A word with the pack's address but an unknown command, out-of-range parameters or a
//!   motor the variant lacks is ignored (counted), with no answer.
//! - Break codes cannot travel in a byte stream; [`TmcpackSim::line_break`] injects one.
//! - The motion state advances in 2 ms ticks on the absolute grid of the given time;
//!   queries see the state of the last tick. [`StreamDevice::next_event`] reports reply
//!   bytes and, while a delayed $28 waits, every tick.
//! - $CC and [`TmcpackSim::power_cycle`] put one 0 byte on the line (5.1, 8.6) and leave the
//!   pack deaf for [`TmcpackSimConfig::boot_time`]; the address comes back from the rotary
//!   switches and the baud rate to 19200.
//! - The response address a host gives must be one no pack on the bus uses: like the
//!   firmware, the model cannot tell a reply from a request, so a reply addressed to a pack
//!   is executed by it.
//! - $15 PiMode makes $23/$29 position with the PI controller; the PI output is limited to
//!   ±vmax and changes by at most amax/64 per tick outside ±vstart (the manual states no
//!   acceleration limit for it). The analogue stop ($31) works whenever its limits are set,
//!   without StopNull. TestNull checks the switch the filter delay (plus T0 with
//!   DelayTestNull) after the motor came to rest at position 0.
//! - Reference search (8.4): actions 20 stopping, 21 seeking the switch (vrefmax with
//!   FastRef, else vmin at divider 3), 22 backing off at vstart until it releases, 23 slow
//!   approach at vmin, 24 crossing it for the far edge (NullCenter: zero at the centre),
//!   25 driving to the new zero ($16 "stop after search"), 30 mechanical reference (5/4 ·
//!   poslimit against [`MotorConfig::travel`]). The fast search stops abruptly on the
//!   switch; zero lies `nulloffset` beyond the edge in the search direction; no switch within
//!   5/4 · poslimit, or none again on the slow approach, restarts the search; afterwards
//!   the motor resumes its previous action (an idle motor drives back to where it started).
//! - CAN (6.2) is the `can` module: the pack is a
//!   [`CanDevice`](motion_link::sim::CanDevice) too, with its 16-command cache at 2 ms a
//!   command; the first valid CAN instruction ends RS-232 / RS-485 control until a reset.
//! - Power-down ($45, "Version 1.46 and since Version 1.49": a firmware revision without it
//!   ignores the word): below [`TmcpackSimConfig::power_down_volts`] the pack enters its
//!   power-down state whether or not bit 2 activated the mode ("The power down state is
//!   independent of bit 2"); activated, it stops every motor at once, saves the positions
//!   in EEPROM (they survive resets and power cycles) and holds the motors (no coil
//!   current, motion commands ignored) until bit 3 resets the state above the level. The
//!   bits of one `$45` are handled in the order load, invalidate, activate, reset (the
//!   manual gives none). [`TmcpackSim::power_outage`] is a supply falling to nothing and
//!   coming back.
//! - `$17`: the table sets the coil currents ([`MotorView::coils`]): the lower 5 bits of
//!   the position point into the 16 entries and their mirror, coil B 16 microsteps on
//!   (`tmcpack::table`); the rotor's motion does not depend on it.
//! - Not modelled: RS-232 forwarding via CAN (6.3; `$44` only stores its settings), thermal
//!   shutdown. The $F2/$F6 magic codes are not published; the config holds invented ones.

mod can;
mod config;
mod firmware;
pub(crate) mod machine;
mod motor;
mod pack;
mod params;
mod ramp;
mod reference;
mod wire;

use core::time::Duration;

use motion_link::sim::StreamDevice;
use tmcpack::convert::{TICK, byte_time, nominal_baud, units};
use tmcpack::{Action, FrameDecoder, MotorMask, RequestFrame, Variant, Word};

use motion_sim::rng::SimRng;

pub use can::CanStats;
pub use config::{MotorConfig, RefSwitch, TmcpackSimConfig};

use motor::{Mode, Motor, TickCtx};
use pack::{NonVolatile, PackState};
use wire::{Kind, Transmitter};

/// Counters of what the simulated pack saw on the wire.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SimStats {
    /// Complete words with this pack's address that it executed.
    pub executed: u64,
    /// Words for other addresses (other packs' requests and replies).
    pub foreign: u64,
    /// Words with this pack's address that did not decode or name a missing motor.
    pub invalid: u64,
    /// Partial words aborted by the packet timeout or a break.
    pub aborted: u64,
    /// Bytes lost because the pack was driving the pair or booting.
    pub lost_bytes: u64,
    /// Answers replaced by a later request's answer before they were sent (7.1 violated).
    pub replaced_replies: u64,
    /// Requests that began while the answer to an earlier one was still due or the pack
    /// still drove the pair (its answer, or the switch-over hold after it): manual 7.1
    /// "Requests must not be interlaced". A real pack garbles them (bytes lost while it
    /// transmits, its one answer buffer overwritten); a host that keeps the rules makes 0.
    pub interlaced: u64,
    /// Answers sent (words put on the transmit queue).
    pub replies: u64,
}

/// A snapshot of one motor for tests and displays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorView {
    /// Position register as $20 reports it.
    pub position: i32,
    /// The rotor's physical position in microsteps (not moved by $27 or referencing).
    pub physical: i64,
    /// Velocity register (vact) as $21 reports it.
    pub velocity: i16,
    /// Velocity in 1/64 units, the $14 accumulator.
    pub velocity_q: i64,
    /// Divider the velocity is in (div_i, or 3 for vmin phases of a reference search).
    pub divider: u8,
    /// Microstep frequency, Hz (signed).
    pub microstep_hz: f64,
    /// Current action.
    pub action: Action,
    /// Target register ($26).
    pub target: i32,
    /// Stop flag (cleared by a $20 read).
    pub stop_flag: bool,
    /// The firmware's (de-bounced) view of the reference switch.
    pub switch_active: bool,
    /// Coil current, A.
    pub coil_current_amps: f64,
    /// Coil A's and coil B's share of that current as the `$17` table gives it at the
    /// position (signed, −255..=255: `tmcpack::table::coil_currents`).
    pub coils: (i16, i16),
}

/// The simulated pack.
#[derive(Debug)]
pub struct TmcpackSim {
    cfg: TmcpackSimConfig,
    rng: SimRng,
    st: PackState,
    motors: [Motor; 6],
    nv: NonVolatile,
    decoder: FrameDecoder,
    tx: Transmitter,
    deaf_until: Option<Duration>,
    next_tick: Option<Duration>,
    supply_volts: f64,
    power_down_state: bool,
    ttlio1_in: bool,
    ready: bool,
    stats: SimStats,
    /// The CAN interface (manual 6.2).
    can: can::CanSide,
    /// The end of the last byte received, and how many came back to back up to it: words
    /// are told apart by the pauses between them (a request is 9 bytes back to back).
    last_rx: Option<Duration>,
    burst: u32,
}

impl TmcpackSim {
    /// A pack as it is after power-on, already booted.
    pub fn new(config: TmcpackSimConfig) -> Self {
        let st = PackState::new(config.address);
        let motors = config
            .motors
            .map(|hw| Motor::new(hw, 0, config.amax_divisor));
        let decoder =
            FrameDecoder::new(units(st.timeout_units), byte_time(nominal_baud(st.divisor)));
        Self {
            rng: SimRng::new(config.seed),
            nv: NonVolatile::new(config.flash_size, config.variant),
            supply_volts: config.supply_volts,
            st,
            motors,
            decoder,
            tx: Transmitter::default(),
            deaf_until: None,
            next_tick: None,
            power_down_state: false,
            ttlio1_in: false,
            ready: true,
            stats: SimStats::default(),
            can: can::CanSide::new(config.can_command_time),
            last_rx: None,
            burst: 0,
            cfg: config,
        }
    }

    /// The configuration the pack was built with.
    pub fn config(&self) -> &TmcpackSimConfig {
        &self.cfg
    }

    /// The address the pack answers to now ($42 changes it, a reset restores it).
    pub fn address(&self) -> u8 {
        self.st.address
    }

    /// SIXpack or QUADpack.
    pub fn variant(&self) -> Variant {
        self.cfg.variant
    }

    /// The line rate the pack listens at.
    pub fn baud_rate(&self) -> u32 {
        nominal_baud(self.st.divisor)
    }

    /// The transmitter switch-over delay ($40).
    pub fn switchover(&self) -> Duration {
        units(self.st.switchover_units)
    }

    /// The packet timeout ($41).
    pub fn packet_timeout(&self) -> Duration {
        units(self.st.timeout_units)
    }

    /// Wire counters.
    pub fn stats(&self) -> SimStats {
        let mut s = self.stats;
        s.aborted = self.decoder.stats().aborted;
        s
    }

    /// One motor (`None` beyond the variant's motors).
    pub fn motor(&self, motor: u8) -> Option<MotorView> {
        let m = self.motors.get(self.index(motor)?)?;
        Some(MotorView {
            position: m.reported(),
            physical: m.phys,
            velocity: m.vact(),
            velocity_q: m.vq,
            divider: m.vdiv,
            microstep_hz: m.microstep_hz(self.st.clkdiv),
            action: m.action(),
            target: m.target,
            stop_flag: m.stop_flag,
            switch_active: m.switch_active,
            coil_current_amps: m.current_amps,
            coils: tmcpack::table::coil_currents(&self.st.table, m.pos),
        })
    }

    /// The 7-segment display: number of active motors, decimal point during a reference
    /// search (manual 2).
    pub fn display(&self) -> (u8, bool) {
        let active = self
            .active_motors()
            .filter(|m| m.action().is_active())
            .count() as u8;
        let dp = self.active_motors().any(|m| m.action().is_referencing());
        (active, dp)
    }

    /// Logic level at TTLOUT1 (the ready output when $32 P3 says so: 1 = ready).
    pub fn ttlout1(&self) -> bool {
        if self.st.ttlout1_ready {
            self.ready
        } else {
            self.st.ttlout1
        }
    }

    /// Level the pack drives at TTLIO1: `Some` when $32 made it an output ("0=output"),
    /// `None` while it is an input.
    pub fn ttlio1_output(&self) -> Option<bool> {
        (!self.st.ttlio1_is_input).then_some(self.st.ttlio1_out)
    }

    /// Whether TTLOUT1 works as the ready output ($32 P3), and the $33 masks.
    pub fn ready_output(&self) -> Option<(MotorMask, MotorMask)> {
        self.st
            .ttlout1_ready
            .then_some((self.st.ready_active, self.st.ready_ref))
    }

    /// A motor's $31 stop limits (left minimum, right maximum).
    pub fn stop_limits(&self, motor: u8) -> Option<(u16, u16)> {
        let m = self.motors.get(self.index(motor)?)?;
        Some((m.p.stop_left_min, m.p.stop_right_max))
    }

    /// Motor positions saved in EEPROM by the power-down mode, if valid.
    pub fn saved_positions(&self) -> Option<[i32; 6]> {
        self.nv.saved_positions
    }

    /// The `$17` motor characteristics table in use (the lower half, common to all motors).
    pub fn microstep_table(&self) -> [u8; 16] {
        self.st.table
    }

    /// `true` while undervoltage has put the pack in the power-down state.
    pub fn power_down_state(&self) -> bool {
        self.power_down_state
    }

    /// Executes `request` at `now` as if another master on the pair had sent it, without
    /// the wire (a request that answers queues its answer as a word would): what a second
    /// program or a hand-held terminal does behind the server's back. The pack is advanced
    /// to `now` first.
    pub fn act_behind_the_back(&mut self, now: Duration, request: tmcpack::Request) {
        self.advance(now);
        self.execute(now, request);
    }

    /// Moves (or removes) a motor's reference switch.
    pub fn set_ref_switch(&mut self, motor: u8, switch: Option<RefSwitch>) {
        if let Some(m) = self.index(motor).and_then(|i| self.motors.get_mut(i)) {
            m.hw.ref_switch = switch;
        }
    }

    /// Sets a motor's mechanical travel range.
    pub fn set_travel(&mut self, motor: u8, travel: Option<(i64, i64)>) {
        if let Some(m) = self.index(motor).and_then(|i| self.motors.get_mut(i)) {
            m.hw.travel = travel;
        }
    }

    /// Sets an analogue input: channels 0..=5 are the motors' A_In, 6 the external input
    /// (7, the supply, follows [`set_supply_volts`](Self::set_supply_volts)).
    pub fn set_analog(&mut self, channel: u8, value: u16) {
        let value = value.min(tmcpack::MAX_ANALOG);
        match channel {
            0..=5 => {
                if let Some(m) = self.motors.get_mut(usize::from(channel)) {
                    m.hw.analog = value;
                }
            }
            6 => self.cfg.external_analog = value,
            _ => {}
        }
    }

    /// Level driven into TTLIO1 from outside (read by $30 when TTLIO1 is an input).
    pub fn set_ttlio1_input(&mut self, level: bool) {
        self.ttlio1_in = level;
    }

    /// Changes the supply voltage at `now` (below the power-down level the pack enters its
    /// power-down state, $45).
    pub fn set_supply_volts(&mut self, now: Duration, volts: f64) {
        self.advance(now);
        self.supply_volts = volts;
        self.check_supply();
    }

    /// A break code on the line: the partial word is aborted (manual 6.1).
    pub fn line_break(&mut self, now: Duration) {
        self.advance(now);
        self.decoder.line_break();
    }

    /// Power off and on at `now`: like $CC, and the physical rotors stay where they are.
    pub fn power_cycle(&mut self, now: Duration) {
        self.advance(now);
        self.hardware_reset(now);
    }

    /// A power outage at `now`: the supply falls through the power-down level (with `$45`
    /// bit 2 activated the pack stops its motors and saves their positions, manual 8.6),
    /// goes off, and comes back at its former voltage: the pack boots as after
    /// [`power_cycle`](Self::power_cycle), the rotors where the outage left them.
    pub fn power_outage(&mut self, now: Duration) {
        let volts = self.supply_volts;
        self.set_supply_volts(now, 0.0);
        self.supply_volts = volts;
        self.power_cycle(now);
    }

    /// Advances the motors to `now` (also done by every wire call).
    pub fn advance(&mut self, now: Duration) {
        let mut next = match self.next_tick {
            Some(t) => t,
            None => (now.as_nanos() / TICK.as_nanos() + 1)
                .try_into()
                .map(|k: u64| Duration::from_nanos(k.saturating_mul(TICK.as_nanos() as u64)))
                .unwrap_or(now),
        };
        while next <= now && next < Duration::MAX {
            if self.quiet() {
                let skip = ((now - next).as_nanos() / TICK.as_nanos()) as u32 + 1;
                next = next.saturating_add(TICK.saturating_mul(skip));
                break;
            }
            self.tick(next);
            next = next.saturating_add(TICK);
        }
        self.next_tick = Some(next);
    }

    fn quiet(&self) -> bool {
        self.st.interp.is_none()
            && self.st.delayed.is_none()
            && self
                .active_motors()
                .enumerate()
                .all(|(i, m)| m.idle() && m.current_settled(&self.ctx(i)))
    }

    fn index(&self, motor: u8) -> Option<usize> {
        (motor < self.cfg.variant.motors()).then_some(usize::from(motor))
    }

    fn active_motors(&self) -> impl Iterator<Item = &Motor> {
        self.motors
            .iter()
            .take(usize::from(self.cfg.variant.motors()))
    }

    fn ctx(&self, i: usize) -> TickCtx {
        let value = self.st.peak.get(i / 2).copied().unwrap_or(0);
        let dip = self.cfg.quadpack_dip_percent.get(i).copied().unwrap_or(100);
        // The power-down state holds the motors ("re-enable the motors", $45 bit 3): no
        // coil current until it is reset.
        let enabled = self.motors_enabled();
        TickCtx {
            clkdiv: self.st.clkdiv,
            peak_amps: if enabled {
                self.cfg.variant.peak_current_amps(value, dip)
            } else {
                0.0
            },
        }
    }

    /// One 2 ms firmware cycle at `t`.
    fn tick(&mut self, t: Duration) {
        self.interpolate();
        for i in 0..usize::from(self.cfg.variant.motors()) {
            let ctx = self.ctx(i);
            if let Some(m) = self.motors.get_mut(i) {
                m.tick(&ctx);
            }
        }
        self.check_supply();
        let (act, refm) = (self.st.ready_active, self.st.ready_ref);
        let busy = self.active_motors().enumerate().any(|(i, m)| {
            let bit = i as u8;
            (act.has(bit) && m.action().is_active())
                || (refm.has(bit) && m.action().is_referencing())
        });
        self.ready = !busy;
        self.check_delayed(t);
    }

    /// Moves a $50 interpolation: the master ramps, the others follow its progress.
    fn interpolate(&mut self) {
        let Some(ip) = self.st.interp else { return };
        let master_ctx = self.ctx(ip.master);
        let Some(master) = self.motors.get_mut(ip.master) else {
            return;
        };
        if master.mode != Mode::Interp {
            self.end_interp(ip);
            return;
        }
        let m_start = ip.start.get(ip.master).copied().unwrap_or(0);
        let m_dist = ip.dist.get(ip.master).copied().unwrap_or(0);
        let target = master.target;
        let arrived = master.ramp_step(i64::from(target), master.p.vmax, &master_ctx);
        let progress = master.pos - m_start;
        let m_vq = master.vq;
        for i in 0..usize::from(self.cfg.variant.motors()) {
            if i == ip.master || !ip.mask.has(i as u8) {
                continue;
            }
            let ctx = self.ctx(i);
            let (start, dist) = (
                ip.start.get(i).copied().unwrap_or(0),
                ip.dist.get(i).copied().unwrap_or(0),
            );
            let Some(m) = self.motors.get_mut(i) else {
                continue;
            };
            if m.mode != Mode::Interp {
                continue;
            }
            let pos = start + mul_div(dist, progress, m_dist);
            let vq = mul_div(m_vq, dist, m_dist);
            m.follow(pos, vq, &ctx);
        }
        if arrived {
            for (i, m) in self.motors.iter_mut().enumerate() {
                if ip.mask.has(i as u8) && m.mode == Mode::Interp {
                    m.halt_now();
                    m.mode = Mode::Inactive;
                    m.on_stopped();
                }
            }
            self.st.interp = None;
        }
    }

    fn end_interp(&mut self, ip: pack::Interp) {
        for (i, m) in self.motors.iter_mut().enumerate() {
            if ip.mask.has(i as u8) && m.mode == Mode::Interp {
                m.mode = Mode::Halt {
                    action: Action::Ramp,
                };
            }
        }
        self.st.interp = None;
    }

    fn check_supply(&mut self) {
        if self.supply_volts < self.cfg.power_down_volts && !self.power_down_state {
            self.power_down_state = true;
            if self.st.power_down_enabled {
                let mut saved = [0i32; 6];
                for (slot, m) in saved.iter_mut().zip(self.motors.iter_mut()) {
                    *slot = m.reported();
                    m.halt_now();
                    m.mode = Mode::Inactive;
                }
                self.st.interp = None;
                self.nv.saved_positions = Some(saved);
            }
        }
    }

    /// Motors accept motion commands (not in an activated power-down state).
    fn motors_enabled(&self) -> bool {
        !(self.power_down_state && self.st.power_down_enabled)
    }

    fn check_delayed(&mut self, t: Duration) {
        let Some(d) = self.st.delayed else { return };
        let busy = self
            .active_motors()
            .enumerate()
            .any(|(i, m)| d.mask.has(i as u8) && m.action().is_active());
        if !busy {
            self.st.delayed = None;
            let reply = self.actions_reply();
            self.send(t, d.reply_to, reply, Kind::Delayed);
        }
    }

    fn byte_time(&self) -> Duration {
        byte_time(self.baud_rate())
    }

    fn on_word(&mut self, t: Duration, w: Word) {
        self.advance(t);
        if self.can.active {
            // "After receiving the first valid instruction via CAN, control via RS 232 or
            // RS 485 will be terminated."
            self.can.stats.serial_ignored += 1;
            return;
        }
        if w[0] != self.st.address {
            self.stats.foreign += 1;
            return;
        }
        match RequestFrame::decode(&w) {
            // "(Version 1.46 and since Version 1.49)": older firmware has no $45.
            Ok(f)
                if matches!(f.request, tmcpack::Request::PowerDown { .. })
                    && !tmcpack::power_down_supported(self.cfg.firmware_revision) =>
            {
                self.stats.invalid += 1;
            }
            Ok(f)
                if f.request
                    .motor()
                    .is_none_or(|m| m < self.cfg.variant.motors()) =>
            {
                self.stats.executed += 1;
                self.execute(t, f.request);
            }
            _ => self.stats.invalid += 1,
        }
    }

    /// A byte ending at `at` reached the pack: when it begins a request (after a pause,
    /// or nine bytes after the last one that did) while an answer is still due or the pack
    /// drives the pair, the request is interlaced ([`SimStats::interlaced`]).
    fn watch_interlace(&mut self, at: Duration) {
        let bt = self.byte_time();
        let back_to_back = self
            .last_rx
            .is_some_and(|last| at.saturating_sub(last) < bt + bt / 2);
        if !back_to_back {
            self.burst = 0;
        }
        // The byte began a byte time before it ended.
        let began = at.saturating_sub(bt);
        let booting = self.deaf_until.is_some_and(|d| at < d);
        if self.burst.is_multiple_of(tmcpack::FRAME_LEN as u32)
            && !booting
            && self.tx.answer_due(began)
        {
            self.stats.interlaced += 1;
        }
        self.burst = self.burst.wrapping_add(1);
        self.last_rx = Some(at);
    }

    /// Draws the noise of one analogue read.
    fn noise(&mut self) -> i32 {
        let n = i32::from(self.cfg.analog_noise_lsb);
        if n == 0 {
            return 0;
        }
        (self.rng.next_u64() % (2 * n as u64 + 1)) as i32 - n
    }
}

/// `a · b / c` without overflow, 0 when `c` is 0.
fn mul_div(a: i64, b: i64, c: i64) -> i64 {
    if c == 0 {
        return 0;
    }
    i64::try_from(i128::from(a) * i128::from(b) / i128::from(c)).unwrap_or(0)
}

impl StreamDevice for TmcpackSim {
    fn receive(&mut self, now: Duration, bytes: &[u8]) {
        let n = bytes.len();
        for (j, &b) in bytes.iter().enumerate() {
            let at = now.saturating_sub(self.byte_time().saturating_mul((n - 1 - j) as u32));
            self.watch_interlace(at);
            if self.deaf_until.is_some_and(|d| at < d) || self.tx.driving(at) {
                self.stats.lost_bytes += 1;
                continue;
            }
            if let Some(w) = self.decoder.push_byte(at, b) {
                self.on_word(at, w);
            }
        }
        self.advance(now);
    }

    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        self.advance(now);
        self.tx.transmit(now, out)
    }

    fn next_event(&self, now: Duration) -> Option<Duration> {
        let tick = self
            .st
            .delayed
            .map(|_| self.next_tick.unwrap_or(now).max(now));
        [
            self.tx.next_byte(),
            tick,
            self.decoder.deadline().filter(|&d| d > now),
            self.deaf_until.filter(|&d| d > now),
        ]
        .into_iter()
        .flatten()
        .min()
    }

    fn baud(&self) -> Option<u32> {
        Some(self.baud_rate())
    }
}
