//! The VERSION register as the driver records it: the firmware description of the
//! board's status ("QSB-M SN 00001 fw 13").

use core::fmt::Write as _;

use ::qsb::ProductType;

use super::QsbDriver;
use crate::state::FIRMWARE_LEN;

impl QsbDriver {
    /// Records the VERSION answer as the firmware description.
    pub(super) fn record_version(&mut self, version: ::qsb::Version) {
        let mut text = motion_base::FixedText::<FIRMWARE_LEN>::new();
        let product = match version.product {
            ProductType::D => 'D',
            ProductType::M => 'M',
            ProductType::S => 'S',
        };
        // The buffer is larger than the longest description; a failure only cuts it.
        let _ = write!(
            text,
            "QSB-{product} SN {:05X} fw {:02X}",
            version.serial, version.firmware
        );
        self.status.set_firmware(text.as_str());
        self.product = Some(version.product);
        self.serial = Some(version.serial);
    }
}
