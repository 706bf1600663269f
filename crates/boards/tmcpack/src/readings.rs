//! The device keys that say how the pack's firmware reads two instructions the manual
//! ("SIXpack / QUADpack manual" V2.43) documents two ways, neither of which the wire tells
//! apart (docs/ARCHITECTURE.md, "How the datasheets are read"; docs/keys/tmcpack.md):
//!
//! - `amax_divisor` (64 or 16, default 64): `$14` "1/64 amax is accumulated with 500Hz
//!   during acceleration to vact" against 7.1's defaults "amax=128; // increments v by
//!   128/16=8 each 2 ms". Under the wrong reading every ramp and every stop is 4× off.
//! - `stop_no_ref_bit` (5 or 6, default 5): `$15` P6 "Bit 5: StopNoRef" in the table
//!   against "StopNoRef(P6, Bit 6)" in the prose (twice); with 6, NullPositive is bit 5.

use motion_board::keys::{DeviceContext, Int, KeyIssues, Spanned};
use tmcpack::{AmaxDivisor, OptionsLayout};

/// `amax_divisor`: 64 or 16; an issue naming both readings for anything else.
pub(crate) fn amax_divisor(
    v: &mut dyn KeyIssues,
    ctx: &DeviceContext,
    value: &Spanned<Int>,
) -> Option<u8> {
    let d = value.get_ref().get();
    match u32::try_from(d).ok().and_then(AmaxDivisor::from_divisor) {
        Some(divisor) => Some(divisor.get() as u8),
        None => {
            v.issue(
                value.span(),
                &ctx.key("amax_divisor"),
                format!(
                    "{d} is not a reading of $14; allowed: 64 (manual 8.3 $14: \"1/64 amax is \
                     accumulated with 500Hz\", the default) or 16 (manual 7.1 defaults: \
                     \"amax=128; // increments v by 128/16=8 each 2 ms\")"
                ),
            );
            None
        }
    }
}

/// `stop_no_ref_bit`: 5 or 6; an issue naming both readings for anything else.
pub(crate) fn stop_no_ref_bit(
    v: &mut dyn KeyIssues,
    ctx: &DeviceContext,
    value: &Spanned<Int>,
) -> Option<u8> {
    let bit = value.get_ref().get();
    match u8::try_from(bit)
        .ok()
        .and_then(OptionsLayout::from_stop_no_ref_bit)
    {
        Some(layout) => Some(layout.stop_no_ref_bit()),
        None => {
            v.issue(
                value.span(),
                &ctx.key("stop_no_ref_bit"),
                format!(
                    "{bit} is not a reading of $15 P6; allowed: 5 (manual 8.3 $15 table: \
                     \"Bit 5: StopNoRef\", \"Bit 6: NullPositive\", the default) or 6 (its \
                     prose: \"StopNoRef(P6, Bit 6)\"; NullPositive is then bit 5)"
                ),
            );
            None
        }
    }
}
