//! The counter-mode keys of a qsb `[[device]]` (`count_mode`, `count_range`,
//! `count_limit`, `index_action`, `index_sync`; docs/keys/qsb.md), validated against the
//! MDR0 table of the "QSB Command List" 1.28 and against what the driver can follow.
//!
//! What is refused, and why:
//! - `count_range` other than `"free-running"` while an axis drives a qsb-m: the -M's moves
//!   are planned in steps from the encoder reading, and a counter that wraps at DTR
//!   (modulo-n), freezes at 0 and DTR (range-limit) or stops at its first carry or borrow
//!   (single-cycle) no longer measures where the shaft is: a move would go the wrong way
//!   or never arrive, a home search would never end.
//! - `count_limit` missing for range-limit and modulo-n (DTR is the limit, and the factory
//!   0x1F3 is not a choice anyone made), or outside 1..=0x7FFFFFFF (every count must be a
//!   positive signed 32-bit count).
//! - `index_action` other than `"none"` without `count_range = "modulo-n"`: an index that
//!   resets or loads a free-running counter makes it jump back once per revolution, which a
//!   position cannot follow; in modulo-n with the revolution's counts as the modulus the
//!   index only re-synchronises the wrap.
//! - `index_sync = "synchronous"` with `count_mode = "step-direction"`: "Asynchronous
//!   index mode is set in non-quadrature modes".

use motion_board::keys::{DeviceContext, KeyIssues};
use motion_board::machine::MachineView;
use qsb::{CountMode, CycleMode, IndexMode};

use super::raw::{RawDevice, choice};
use crate::{QsbDeviceKeys, QsbInputMode};

/// Largest `count_limit`: counts stay positive signed 32-bit values.
pub(crate) const MAX_COUNT_LIMIT: i64 = i32::MAX as i64;

/// Validates the counter keys of one device into `keys`.
pub(crate) fn device_keys(
    v: &mut dyn KeyIssues,
    ctx: &DeviceContext,
    raw: &RawDevice,
    keys: &mut QsbDeviceKeys,
) {
    if let Some(value) = &raw.count_mode {
        let allowed = [
            ("x4", CountMode::X4),
            ("x2", CountMode::X2),
            ("x1", CountMode::X1),
            ("step-direction", CountMode::NonQuadrature),
        ];
        keys.count_mode = choice(v, value, &ctx.key("count_mode"), &allowed);
    }
    if let Some(value) = &raw.count_range {
        let allowed = [
            ("free-running", CycleMode::FreeRunning),
            ("single-cycle", CycleMode::SingleCycle),
            ("range-limit", CycleMode::RangeLimit),
            ("modulo-n", CycleMode::ModuloN),
        ];
        keys.count_range = choice(v, value, &ctx.key("count_range"), &allowed);
    }
    let needs_limit = matches!(
        keys.count_range,
        Some(CycleMode::RangeLimit | CycleMode::ModuloN)
    );
    if let Some(value) = &raw.count_limit {
        keys.count_limit = v
            .int_in(value, &ctx.key("count_limit"), 1..=MAX_COUNT_LIMIT)
            .and_then(|limit| u32::try_from(limit).ok());
        if !needs_limit && raw.count_range.is_none() {
            v.warn(
                value.span(),
                &ctx.key("count_limit"),
                "has no effect: count_range is \"free-running\" (set count_range = \"range-limit\" or \"modulo-n\")",
            );
        } else if !needs_limit && keys.count_range.is_some() {
            v.warn(
                value.span(),
                &ctx.key("count_limit"),
                "has no effect: only \"range-limit\" and \"modulo-n\" use DTR as a limit",
            );
        }
    }
    if let (true, None, Some(range)) = (needs_limit, &raw.count_limit, &raw.count_range) {
        v.issue(
            range.span(),
            &ctx.key("count_range"),
            format!(
                "{:?} needs count_limit (DTR, 1..={MAX_COUNT_LIMIT}): range-limit counts between 0 and it, modulo-n runs 0..=count_limit (\"divided by a factor of (DTR + 1)\")",
                range.get_ref()
            ),
        );
    }
    if let Some(value) = &raw.index_action {
        let allowed = [
            ("none", IndexMode::Disabled),
            ("reset", IndexMode::ResetCntr),
            ("load", IndexMode::LoadCntr),
        ];
        keys.index_action = choice(v, value, &ctx.key("index_action"), &allowed);
        let acts = keys.index_action.is_some_and(|a| a != IndexMode::Disabled);
        if acts && keys.count_range != Some(CycleMode::ModuloN) {
            v.issue(
                value.span(),
                &ctx.key("index_action"),
                "needs count_range = \"modulo-n\": an index that resets or loads the counter otherwise makes the position jump back once per revolution; with count_limit = the revolution's counts - 1 it only re-synchronises the wrap",
            );
        }
    }
    if let Some(value) = &raw.index_sync {
        let allowed = [("synchronous", true), ("asynchronous", false)];
        keys.index_sync = choice(v, value, &ctx.key("index_sync"), &allowed);
        if keys.index_sync == Some(true) && keys.count_mode == Some(CountMode::NonQuadrature) {
            v.issue(
                value.span(),
                &ctx.key("index_sync"),
                "a synchronous index needs A and B in quadrature; \"Asynchronous index mode is set in non-quadrature modes\" (MDR0 B6): use \"asynchronous\" or leave it out",
            );
        }
    }
}

/// Counter modes that need the whole device: a range other than free-running on a qsb-m
/// whose axis drives its stepper (`drive`), and counter keys on a device that does not
/// count (PWM, analog).
pub(crate) fn cross_check(
    v: &mut dyn KeyIssues,
    machine: &MachineView<'_>,
    index: usize,
    raw: &RawDevice,
    keys: &QsbDeviceKeys,
    drive: bool,
) {
    let Some(device) = machine.devices.get(index) else {
        return;
    };
    let dkey = |k: &str| format!("device[{}].{k}", device.index);
    if let (Some(value), Some(range), true) = (&raw.count_range, keys.count_range, drive)
        && range != CycleMode::FreeRunning
    {
        v.issue(
            value.span(),
            &dkey("count_range"),
            format!(
                "{:?} cannot count for an axis that drives qsb-m `{}`: its moves are planned from the encoder reading, and a counter that wraps, freezes at its limits or stops at a carry no longer measures the shaft; use it on a qsb-s or qsb-d (a measuring axis), or keep \"free-running\"",
                value.get_ref(),
                device.name
            ),
        );
    }
    if keys.input_mode.unwrap_or_default() != QsbInputMode::Quadrature {
        let set = [
            ("count_mode", raw.count_mode.as_ref().map(|s| s.span())),
            ("count_range", raw.count_range.as_ref().map(|s| s.span())),
            ("count_limit", raw.count_limit.as_ref().map(|s| s.span())),
            ("index_action", raw.index_action.as_ref().map(|s| s.span())),
            ("index_sync", raw.index_sync.as_ref().map(|s| s.span())),
        ];
        for (key, span) in set {
            if let Some(span) = span {
                v.warn(
                    span,
                    &dkey(key),
                    "has no effect: input_mode is not \"quadrature\" (the counter counts nothing)",
                );
            }
        }
    }
}
