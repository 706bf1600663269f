//! Splits each `[[device]]` and `[[axis]]` table of the file into the server's general keys
//! (read by `raw.rs`'s serde structs) and the board's own ([`BoardTables`], read by the
//! board's crate through `motion_board::Board::device_keys` / `axis_keys`). An axis's
//! `home` table is split the same way: its general keys stay, the rest goes to the board
//! as a `home` table of its own (present, maybe empty, whenever the axis has a `home`).

use motion_board::keys::{KeyTable, Spanned};
use toml::de::{DeTable, DeValue};

/// The general keys of a `[[device]]`.
pub(crate) const DEVICE_KEYS: &[&str] = &["name", "link", "model", "address", "sim"];

/// The general keys of an `[[axis]]`.
pub(crate) const AXIS_KEYS: &[&str] = &[
    "name",
    "device",
    "channel",
    "unit",
    "counts_per_unit",
    "min",
    "max",
    "max_velocity",
    "max_accel",
    "position_tolerance",
    "home",
    "following_error",
    "overspeed_factor",
    "estop",
];

/// The general keys of an axis's `home` table.
pub(crate) const HOME_KEYS: &[&str] = &["direction", "max_travel", "position"];

/// The boards' keys of every `[[device]]` and `[[axis]]` table, by the table's index in the
/// file (a table that is no table at all has an empty one: serde reports it).
#[derive(Debug, Default)]
pub(crate) struct BoardTables<'a> {
    /// Per `[[device]]`.
    pub devices: Vec<KeyTable<'a>>,
    /// Per `[[axis]]`.
    pub axes: Vec<KeyTable<'a>>,
}

/// Takes the boards' keys out of `doc`'s `[[device]]` and `[[axis]]` tables.
pub(crate) fn split<'a>(doc: &mut Spanned<DeTable<'a>>) -> BoardTables<'a> {
    let mut tables = BoardTables::default();
    for (key, value) in doc.get_mut().iter_mut() {
        let (is_device, is_axis) = match key.get_ref().as_ref() {
            "device" => (true, false),
            "axis" => (false, true),
            _ => continue,
        };
        let DeValue::Array(items) = value.get_mut() else {
            continue;
        };
        for item in items.iter_mut() {
            let span = item.span();
            let board = match item.get_mut() {
                DeValue::Table(table) if is_device => take(table, DEVICE_KEYS),
                DeValue::Table(table) if is_axis => {
                    let mut board = take(table, AXIS_KEYS);
                    if let Some((home_key, home)) = table
                        .iter_mut()
                        .find(|(k, _)| k.get_ref().as_ref() == "home")
                        && let DeValue::Table(home_table) = home.get_mut()
                    {
                        let rest = take(home_table, HOME_KEYS);
                        board.insert(
                            home_key.clone(),
                            Spanned::new(home.span(), DeValue::Table(rest)),
                        );
                    }
                    board
                }
                _ => DeTable::new(),
            };
            let table = KeyTable::new(Spanned::new(span, board));
            if is_device {
                tables.devices.push(table);
            } else {
                tables.axes.push(table);
            }
        }
    }
    tables
}

/// Moves every key of `table` that is not one of `keep` into the table returned.
fn take<'a>(table: &mut DeTable<'a>, keep: &[&str]) -> DeTable<'a> {
    let mut taken = DeTable::new();
    let all = core::mem::take(table);
    for (key, value) in all {
        if keep.contains(&key.get_ref().as_ref()) {
            table.insert(key, value);
        } else {
            taken.insert(key, value);
        }
    }
    taken
}

#[cfg(test)]
mod tests {
    use super::split;
    use toml::de::DeTable;

    #[test]
    fn board_keys_leave_the_general_tables_with_their_place_in_the_file() {
        let source = "[[device]]\nname = \"p\"\nmodel = \"tmcpack\"\nvariant = \"quadpack\"\n\n[[axis]]\nname = \"x\"\ncurrent = { peak = 50 }\nhome = { direction = \"positive\", input = \"edge\" }\n\n[[axis]]\nname = \"y\"\nhome = { direction = \"negative\" }\n";
        let mut doc = DeTable::parse(source).expect("toml");
        let tables = split(&mut doc);
        let keys = |t: &motion_board::keys::KeyTable<'_>| -> Vec<String> {
            t.keys().map(|(k, _)| k.to_owned()).collect()
        };
        assert_eq!(keys(&tables.devices[0]), ["variant"]);
        assert_eq!(keys(&tables.axes[0]), ["current", "home"]);
        assert_eq!(
            keys(&tables.axes[1]),
            ["home"],
            "an empty home table still says one is there"
        );
        let (_, span) = tables.devices[0].keys().next().expect("variant");
        assert_eq!(&source[span], "\"quadpack\"");
        let general = toml::de::Deserializer::from(doc);
        let value: toml::Table = serde::Deserialize::deserialize(general).expect("general keys");
        let device = &value["device"][0];
        assert!(device.get("variant").is_none() && device.get("model").is_some());
        let home = &value["axis"][0]["home"];
        assert!(home.get("input").is_none() && home.get("direction").is_some());
    }
}
