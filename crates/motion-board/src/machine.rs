//! The validated machine as a board's cross-checks see it ([`MachineView`]): every link,
//! device, axis and signal the server validated, with where each was written, so that a
//! board can check what no single table shows (two packs answering to one address, motor
//! pairs sharing a peak current, a pin used twice) and name the key at fault.

use motion_base::{LinkFraming, LinkKind, Model, SignalKind};
use motion_drivers::Pin;
use motion_drivers::spec::MachineKeys;

use crate::keys::{KeyTable, Span};

/// One validated `[[link]]`.
#[derive(Debug, Clone)]
pub struct LinkView<'a> {
    /// Its index in the file.
    pub index: usize,
    /// Its name.
    pub name: &'a str,
    /// Stream or SPI.
    pub kind: LinkKind,
    /// Bytes, or CAN frames (a `socketcan` or `sim-can` link).
    pub framing: LinkFraming,
    /// Its line rate: the baud of a serial or serial sim link, the clock of a spidev or SPI
    /// sim link, the bit rate of a CAN link; `None` for an SPI socket (its peer sets the
    /// clock).
    pub line_rate: Option<u32>,
    /// Where the rate was written (`baud` or `speed_hz`), if it was.
    pub rate_span: Option<Span>,
}

/// One validated `[[device]]`.
#[derive(Debug, Clone)]
pub struct DeviceView<'a> {
    /// Its index in the file.
    pub index: usize,
    /// Its name.
    pub name: &'a str,
    /// Index of its link in [`MachineView::links`].
    pub link: usize,
    /// Its model.
    pub model: Model,
    /// Its bus address (0 for a model without addresses).
    pub address: u32,
    /// Where `address` was written, if it was.
    pub address_span: Option<Span>,
    /// The whole table.
    pub table: Span,
    /// Its validated machine keys.
    pub machine: &'a MachineKeys,
    /// Its board keys as written (a board re-reads them for their spans).
    pub keys: &'a KeyTable<'a>,
}

/// One validated `[[axis]]`.
#[derive(Debug, Clone)]
pub struct AxisView<'a> {
    /// Its index in the file.
    pub index: usize,
    /// Its name.
    pub name: &'a str,
    /// Index of its device in [`MachineView::devices`].
    pub device: usize,
    /// The channel it drives.
    pub channel: usize,
    /// Its `counts_per_unit` (board counts per unit of its positions).
    pub counts_per_unit: f64,
    /// Its unit.
    pub unit: &'a str,
    /// The whole table.
    pub table: Span,
    /// Where its `device` key was written.
    pub device_span: Span,
    /// Its validated machine keys.
    pub machine: &'a MachineKeys,
    /// Its board keys as written.
    pub keys: &'a KeyTable<'a>,
}

/// One validated `[[signal]]`.
#[derive(Debug, Clone)]
pub struct SignalView<'a> {
    /// Its index in the file.
    pub index: usize,
    /// Its name.
    pub name: &'a str,
    /// Index of its device in [`MachineView::devices`].
    pub device: usize,
    /// What it is used as.
    pub kind: SignalKind,
    /// The pin (an index into its device's pin table).
    pub pin: Pin,
    /// The pin's name (`"ttlout1"`).
    pub pin_name: &'a str,
    /// Where its `pin` was written.
    pub pin_span: Span,
    /// Where its `kind` was written.
    pub kind_span: Span,
    /// The whole table.
    pub table: Span,
}

/// The validated machine, for the boards' cross-checks.
#[derive(Debug, Clone, Default)]
pub struct MachineView<'a> {
    /// Every valid link, in file order.
    pub links: Vec<LinkView<'a>>,
    /// Every valid device, in file order.
    pub devices: Vec<DeviceView<'a>>,
    /// Every valid axis, in file order.
    pub axes: Vec<AxisView<'a>>,
    /// Every valid signal, in file order.
    pub signals: Vec<SignalView<'a>>,
}

impl<'a> MachineView<'a> {
    /// The devices of `model`, with their index in [`devices`](Self::devices).
    pub fn devices_of(&self, model: Model) -> impl Iterator<Item = (usize, &DeviceView<'a>)> {
        self.devices
            .iter()
            .enumerate()
            .filter(move |(_, device)| device.model == model)
    }

    /// The axes on device `device` (an index into [`devices`](Self::devices)).
    pub fn axes_on(&self, device: usize) -> impl Iterator<Item = &AxisView<'a>> {
        self.axes.iter().filter(move |axis| axis.device == device)
    }

    /// The signals on device `device`.
    pub fn signals_on(&self, device: usize) -> impl Iterator<Item = &SignalView<'a>> {
        self.signals
            .iter()
            .filter(move |signal| signal.device == device)
    }
}
