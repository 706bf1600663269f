//! The board registry: one list of the board crates this build of motiond drives (the
//! `registry!` invocation below), and what is made from it: [`BOARDS`] (every board as a
//! `dyn Board`, for start-up), [`AnyDriver`] (an enum of every board's driver: what the
//! server's tick holds, static dispatch without a box), and the lookups every user of the
//! list needs (by config id, by contract code, by model). Adding a board is its crate, one
//! line in the list and one dependency line in this crate's `Cargo.toml`
//! (docs/ARCHITECTURE.md "How to add a board").
#![warn(missing_docs)]
#![forbid(unsafe_code)]

#[macro_use]
mod any_driver;

use motion_base::Model;
pub use motion_board::{Board, LinkFacts, SimBoard, TypedBoard};
use motion_drivers::spec::{DriverSpec, SpecError};

registry! {
    /// Every board this build drives, in contract-code order (the board type: a unit
    /// struct implementing `Board` and `TypedBoard`).
    Qq2drv => board_qq2drv::Qq2drvBoard,
    Tmcpack => board_tmcpack::TmcpackBoard,
    Spimotor => board_spimotor::SpimotorBoard,
    Qsb => board_qsb::QsbBoard,
    Example => board_example::ExampleBoard,
}

/// The board of `model`. Every [`Model`] the server sees comes from [`BOARDS`] (the
/// config names models by id: [`by_id`]), so this finds one.
///
/// # Panics
/// For a model of a board crate this build does not list: a programming error (a
/// driver or test built outside the registry handed it in).
#[must_use]
pub fn board(model: Model) -> &'static dyn Board {
    BOARDS
        .iter()
        .copied()
        .find(|board| board.model() == model)
        .unwrap_or_else(|| panic!("board {model} is not in the registry (motion_boards::BOARDS)"))
}

/// The board whose config id is `id` (`model = "tmcpack"`).
#[must_use]
pub fn by_id(id: &str) -> Option<&'static dyn Board> {
    BOARDS
        .iter()
        .copied()
        .find(|board| board.model().id() == id)
}

/// The board whose contract code is `code` (`DeviceInfo::model`).
#[must_use]
pub fn by_code(code: u32) -> Option<&'static dyn Board> {
    BOARDS
        .iter()
        .copied()
        .find(|board| board.model().code() == code)
}

/// The config ids of every board, for messages: `qq2drv, tmcpack, spimotor, qsb`.
#[must_use]
pub fn id_list() -> String {
    BOARDS
        .iter()
        .map(|board| board.model().id())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The config ids of the boards `keep` keeps, for messages, the last joined with `word`:
/// `ids(spi, "and")` = `qq2drv and spimotor`.
#[must_use]
pub fn ids(keep: impl Fn(&dyn Board) -> bool, word: &str) -> String {
    let ids: Vec<&str> = BOARDS
        .iter()
        .copied()
        .filter(|board| keep(*board))
        .map(|board| board.model().id())
        .collect();
    match ids.split_last() {
        None => String::new(),
        Some((last, [])) => (*last).to_owned(),
        Some((last, rest)) => format!("{} {word} {last}", rest.join(", ")),
    }
}

#[cfg(test)]
mod tests {
    use super::{BOARDS, Board, board, by_code, by_id, id_list, ids};

    #[test]
    fn ids_and_codes_are_unique_and_found() {
        for (index, entry) in BOARDS.iter().enumerate() {
            let model = entry.model();
            assert_ne!(model.code(), 0, "{model}: code 0 means \"no model\"");
            assert!(
                !model.id().is_empty()
                    && model
                        .id()
                        .bytes()
                        .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-'),
                "{model}: a config id is lower case"
            );
            for other in &BOARDS[..index] {
                assert_ne!(other.model().code(), model.code(), "{model}: code taken");
                assert_ne!(other.model().id(), model.id(), "{model}: id taken");
            }
            assert_eq!(by_id(model.id()).map(|b| b.model()), Some(model));
            assert_eq!(by_code(model.code()).map(|b| b.model()), Some(model));
            assert_eq!(board(model).model(), model);
        }
        assert!(by_id("nonesuch").is_none());
        assert!(by_code(0).is_none());
        // Properties, not the literal list: a board added to BOARDS needs no edit here.
        let every: Vec<&str> = BOARDS.iter().map(|b| b.model().id()).collect();
        assert_eq!(id_list().split(", ").collect::<Vec<_>>(), every);
        assert!(id_list().starts_with("qq2drv, tmcpack, spimotor, qsb"));
        let pair = |b: &dyn Board| ["tmcpack", "spimotor"].contains(&b.model().id());
        assert_eq!(ids(pair, "or"), "tmcpack or spimotor");
        let three = |b: &dyn Board| ["qq2drv", "tmcpack", "qsb"].contains(&b.model().id());
        assert_eq!(ids(three, "and"), "qq2drv, tmcpack and qsb");
        assert!(
            ids(|b| b.link().shared, "or").contains("tmcpack"),
            "the Trinamic packs share an RS-485 bus"
        );
        assert_eq!(ids(|b| b.model().id() == "qsb", "or"), "qsb");
        assert_eq!(ids(|_| false, "or"), "");
    }

    #[test]
    fn every_board_has_a_line_rate_and_an_spi_mode_in_range() {
        for entry in BOARDS {
            let link = entry.link();
            assert!(link.default_rate > 0, "{}", entry.model());
            assert!(link.spi_mode <= 3, "{}", entry.model());
        }
    }

    #[test]
    fn codes_run_in_list_order() {
        // BOARDS is in contract-code order (its docs): a new board goes at the end.
        for pair in BOARDS.windows(2) {
            assert!(pair[0].model().code() < pair[1].model().code());
        }
    }
}
