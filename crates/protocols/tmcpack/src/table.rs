//! The `$17` motor characteristics table (manual 8.1 "Adapting the microstep-table to the
//! motor characteristics", 8.3 "Write motor characteristics Table").
//!
//! "The lower 5 bits of the position counter of each motor are used as a pointer into the
//! symmetrical characteristics table and determine the current for coil A of the motor. The
//! current for coil B is determined from the same table by a pointer shifted by 16 steps.
//! For customizing the table can be modified for all motors in common. Therefore only the
//! lower half (16 entries) has to be programmed." `$17` carries four entries at a time from
//! a pointer 0, 4, 8 or 12, so a whole table is four requests ([`table_requests`]).
//!
//! Our reading of "symmetrical" (the manual draws the curve but gives no formula): the 32
//! entries a 5-bit pointer reaches are the 16 programmed ones followed by the same in
//! reverse (entry 31 − i = entry i), half a sine period for the default table; the sign of
//! the coil current changes every 32 microsteps (bit 5 of the pointer's position), which
//! makes a full electrical period of 64 microsteps = 4 full steps of 16 microsteps.

use crate::Request;

/// Entries of the table `$17` programs (the lower half).
pub const TABLE_LEN: usize = 16;

/// The factory table, "Default-table: 255 * SIN([0.5..15.5]/32*PI)", rounded.
pub const SINE_TABLE: [u8; TABLE_LEN] = [
    13, 37, 62, 86, 109, 131, 152, 171, 189, 205, 219, 231, 240, 247, 252, 255,
];

/// The table of full-step operation the manual names as an example: "table=255, 255,…,
/// 255 -> full step".
pub const FULL_STEP_TABLE: [u8; TABLE_LEN] = [255; TABLE_LEN];

/// The four `$17` requests that program `table`: pointers 0, 4, 8 and 12 with four entries
/// each ("P0 pointer to the table (start = 0,4,8 or 12)", "P1..P4 4 table entries").
pub fn table_requests(table: &[u8; TABLE_LEN]) -> [Request; 4] {
    core::array::from_fn(|k| {
        let at = 4 * k;
        Request::MicrostepTable {
            pointer: at as u8,
            entries: [table[at], table[at + 1], table[at + 2], table[at + 3]],
        }
    })
}

/// The table entry and sign for a microstep position (see the module docs for the
/// reading): magnitude from the symmetric 32-entry table at the position's lower 5 bits,
/// negative in the odd half periods.
fn coil(table: &[u8; TABLE_LEN], position: i64) -> i16 {
    let index = position.rem_euclid(64) as usize;
    let i = index % 32;
    let mirrored = if i < TABLE_LEN { i } else { 31 - i };
    let magnitude = i16::from(table.get(mirrored).copied().unwrap_or(0));
    if index < 32 { magnitude } else { -magnitude }
}

/// The currents of coil A and coil B at `position` (microsteps), as signed table values
/// −255..=255 of the peak current: A from the position's pointer, B from the pointer
/// "shifted by 16 steps".
pub fn coil_currents(table: &[u8; TABLE_LEN], position: i64) -> (i16, i16) {
    (
        coil(table, position),
        coil(table, position.wrapping_add(16)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_table_is_the_manuals_sine() {
        for (i, &entry) in SINE_TABLE.iter().enumerate() {
            let x = (i as f64 + 0.5) / 32.0 * core::f64::consts::PI;
            assert_eq!(f64::from(entry), (255.0 * x.sin()).round());
        }
    }

    #[test]
    fn coil_b_is_coil_a_a_quarter_period_later() {
        // Position 0: A at sin(0.5/32 π), B at sin(16.5/32 π) (entry 15, mirrored).
        assert_eq!(coil_currents(&SINE_TABLE, 0), (13, 255));
        // A quarter period (16 microsteps) later A is where B was.
        assert_eq!(coil_currents(&SINE_TABLE, 16).0, 255);
        // Half a period: the sign of A changes.
        assert_eq!(coil_currents(&SINE_TABLE, 32).0, -13);
        assert_eq!(coil_currents(&SINE_TABLE, -1), (-13, 255));
        // Full step: both coils at 255, their signs alternating by full steps of 16.
        assert_eq!(coil_currents(&FULL_STEP_TABLE, 5), (255, 255));
        assert_eq!(coil_currents(&FULL_STEP_TABLE, 20), (255, -255));
    }
}
