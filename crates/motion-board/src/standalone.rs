//! A board served alone by the `motion-sim` tool (package `motion-sim-cli`): no config
//! file, only its command-line options ([`StandaloneSim`]). Each board takes the options it
//! has and refuses the others ([`StandaloneError`]); [`StandaloneHelp`] is its part of
//! `motion-sim --help`.

use motion_base::Model;
use thiserror::Error;

/// The command-line options of one `--model` of `motion-sim`, and the link it is served on.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct StandaloneSim {
    /// `--address`: its bus address, if given.
    pub address: Option<u8>,
    /// `--variant`: its product variant, as typed, if given.
    pub variant: Option<String>,
    /// `--drive`: the motors it drives, as typed, if given.
    pub drive: Option<String>,
    /// `--seed`: the seed of its random effects, if given (else the model's own).
    pub seed: Option<u64>,
    /// `--baud`: the rate the pseudo-terminal runs at, if given (a board that can start at
    /// another rate than its factory one is set to start at it).
    pub baud: Option<u32>,
    /// `--spi-hz`: the SPI clock the socket counts wire time at, Hz.
    pub spi_hz: u32,
}

impl StandaloneSim {
    /// Refuses the first of `options` (`"address"`, `"variant"`, `"drive"`) that was given:
    /// the ones `model` does not have.
    ///
    /// # Errors
    /// [`StandaloneError::NoSuchOption`] for the first option given.
    pub fn refuse(&self, model: Model, options: &[&'static str]) -> Result<(), StandaloneError> {
        for &option in options {
            let given = match option {
                "address" => self.address.is_some(),
                "variant" => self.variant.is_some(),
                "drive" => self.drive.is_some(),
                _ => false,
            };
            if given {
                return Err(StandaloneError::NoSuchOption {
                    model: model.id(),
                    option,
                });
            }
        }
        Ok(())
    }
}

/// Why a board refuses its command-line options.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum StandaloneError {
    /// The board has no such option (`--model qq2drv has no --address`).
    #[error("--model {model} has no --{option}")]
    NoSuchOption {
        /// The model's id.
        model: &'static str,
        /// The option, without its dashes.
        option: &'static str,
    },
    /// The board has the option but not this value; `message` says which values it takes
    /// (`tmcpack --variant hexpack: use sixpack or quadpack`).
    #[error("{message}")]
    Invalid {
        /// The option, without its dashes.
        option: &'static str,
        /// What is wrong and what to use instead.
        message: String,
    },
}

/// A board's part of `motion-sim --help`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StandaloneHelp {
    /// One line: the product, its wire and its rate.
    pub summary: &'static str,
    /// The options it takes (`--address, --variant sixpack|quadpack`), or `""`.
    pub options: &'static str,
    /// Example command lines, each followed by indented lines saying what it serves and
    /// how to talk to it (the tool indents every line by two more); `""` for none.
    pub examples: &'static str,
}
