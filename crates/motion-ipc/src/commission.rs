//! What a `Commission` request changes ([`CommissionWhat`], its `values[0]`) and the request
//! itself ([`CommandRequest::commission`]).

use crate::{ClientId, CommandKind, CommandRequest, Target, UnknownValue};

enumeration! {
    /// What a [`CommandKind::Commission`] request changes. Travels as `values[0]` of the
    /// request (`1.0`, `2.0`, `3.0`); `values[1]` carries the new value.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum CommissionWhat(u32) -> name {
        /// The device's bus address (`values[1]`, as the config's `address` takes it): the
        /// Trinamic pack's `$42`, the SPI_motor's 0xf1/0xf2/0xf0 sequence.
        Address = 1 => "address",
        /// The device's line rate in baud (`values[1]`): the Trinamic pack's `$40`; the link
        /// follows.
        Baud = 2 => "baud",
        /// Back to the factory settings (`values[1]` unused): the Trinamic pack's `$CC`.
        FactoryReset = 3 => "factory-reset",
    }
}

impl CommissionWhat {
    /// From `values[0]` of a request: an exact small integer.
    pub fn from_value(value: f64) -> Result<Self, UnknownValue> {
        if value.fract() != 0.0 || !(0.0..=f64::from(u32::MAX)).contains(&value) {
            return Err(UnknownValue(u32::MAX));
        }
        Self::try_from(value as u32)
    }
}

impl CommandRequest {
    /// A `Commission` request of device `device` (config order): `what` with `value` (the
    /// new address or baud rate; 0 for a factory reset).
    pub const fn commission(
        client: ClientId,
        sequence: u64,
        device: u32,
        what: CommissionWhat,
        value: u32,
    ) -> Self {
        let mut request = Self::new(client, sequence, device, CommandKind::Commission);
        request.target = Target::Device as u32;
        request.values = [what as u32 as f64, value as f64, 0.0];
        request
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_round_trips_and_the_request_says_device_and_values() {
        for what in CommissionWhat::ALL {
            assert_eq!(CommissionWhat::try_from(what as u32), Ok(what));
            assert_eq!(CommissionWhat::from_value(f64::from(what as u32)), Ok(what));
        }
        assert!(CommissionWhat::try_from(0).is_err());
        assert!(CommissionWhat::from_value(1.5).is_err());
        assert!(CommissionWhat::from_value(-1.0).is_err());
        let request =
            CommandRequest::commission(ClientId::NONE, 7, 2, CommissionWhat::Baud, 115_200);
        assert_eq!(request.kind(), Ok(CommandKind::Commission));
        assert_eq!(request.target(), Ok(Target::Device));
        assert_eq!((request.axis, request.values), (2, [2.0, 115_200.0, 0.0]));
    }
}
