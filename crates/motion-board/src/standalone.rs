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
                _ => self.text(option).is_some(),
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

    /// What `allowed` pairs with the text of `--{option}` (`"variant"`, `"drive"`);
    /// `default` when it was not given.
    ///
    /// # Errors
    /// [`StandaloneError::Invalid`] for any other text: `{model} --{option} {text}: {hint}`
    /// (`hint`: what to use instead, `use sixpack or quadpack`).
    pub fn choice<T: Copy>(
        &self,
        model: Model,
        option: &'static str,
        allowed: &[(&str, T)],
        default: T,
        hint: &str,
    ) -> Result<T, StandaloneError> {
        let Some(text) = self.text(option) else {
            return Ok(default);
        };
        match allowed.iter().find(|(name, _)| *name == text) {
            Some(&(_, value)) => Ok(value),
            None => Err(StandaloneError::Invalid {
                option,
                message: format!("{} --{option} {text}: {hint}", model.id()),
            }),
        }
    }

    /// The text of option `option` (`"variant"`, `"drive"`), if given.
    fn text(&self, option: &str) -> Option<&str> {
        match option {
            "variant" => self.variant.as_deref(),
            "drive" => self.drive.as_deref(),
            _ => None,
        }
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

#[cfg(test)]
mod tests {
    use super::{StandaloneError, StandaloneSim};
    use motion_base::Model;

    #[test]
    fn choice_names_the_value_the_default_or_what_to_use() {
        let allowed = [("stepper", 1), ("brushed", 2)];
        let hint = "use stepper or brushed";
        let choose = |drive: Option<&str>| {
            let options = StandaloneSim {
                drive: drive.map(str::to_owned),
                ..StandaloneSim::default()
            };
            options.choice(Model::SPIMOTOR, "drive", &allowed, 1, hint)
        };
        assert_eq!(choose(None), Ok(1));
        assert_eq!(choose(Some("brushed")), Ok(2));
        assert_eq!(
            choose(Some("servo")),
            Err(StandaloneError::Invalid {
                option: "drive",
                message: "spimotor --drive servo: use stepper or brushed".to_owned(),
            })
        );
    }
}
