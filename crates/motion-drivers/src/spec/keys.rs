//! A model's machine keys as the server validated them, held opaquely ([`MachineKeys`]):
//! each board's crate defines its typed keys (`None` fields: not set, the driver's default
//! applies; values in the config's terms, which its driver converts).

use core::any::Any;
use core::fmt;
use std::sync::Arc;

/// A device's or an axis's model-specific keys, validated: whatever typed struct its
/// board's crate defines (`TmcpackDeviceKeys`, `Qq2drvAxisKeys`, …), or none. The board
/// that validated the keys reads them back with [`get`](Self::get); nobody else needs to
/// know their type, so a board brings its keys without a variant here.
#[derive(Clone, Default)]
pub struct MachineKeys(Option<Arc<dyn AnyKeys>>);

/// The device-level [`MachineKeys`] (a `[[device]]`'s model keys).
pub type DeviceMachine = MachineKeys;
/// The axis-level [`MachineKeys`] (an `[[axis]]`'s model keys).
pub type AxisMachine = MachineKeys;

/// What keys a [`MachineKeys`] can hold: any comparable, printable, shareable value.
trait AnyKeys: Any + fmt::Debug + Send + Sync {
    fn as_any(&self) -> &dyn Any;
    fn same_as(&self, other: &dyn AnyKeys) -> bool;
}

impl<T: Any + fmt::Debug + PartialEq + Send + Sync> AnyKeys for T {
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn same_as(&self, other: &dyn AnyKeys) -> bool {
        other.as_any().downcast_ref::<T>() == Some(self)
    }
}

impl MachineKeys {
    /// No model keys (a model that has none).
    pub const PLAIN: Self = Self(None);

    /// `keys`, as a board's crate validated them.
    pub fn new<T: Any + fmt::Debug + PartialEq + Send + Sync>(keys: T) -> Self {
        Self(Some(Arc::new(keys)))
    }

    /// The keys, when they are a `T`.
    pub fn get<T: Any>(&self) -> Option<&T> {
        self.0.as_deref()?.as_any().downcast_ref::<T>()
    }

    /// The keys as a `T`, or `T`'s default (every key unset) when they are none or another
    /// type.
    pub fn get_or_default<T: Any + Clone + Default>(&self) -> T {
        self.get::<T>().cloned().unwrap_or_default()
    }
}

impl PartialEq for MachineKeys {
    fn eq(&self, other: &Self) -> bool {
        match (&self.0, &other.0) {
            (None, None) => true,
            (Some(a), Some(b)) => a.same_as(b.as_ref()),
            _ => false,
        }
    }
}

impl fmt::Debug for MachineKeys {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.0 {
            None => f.write_str("MachineKeys::PLAIN"),
            Some(keys) => keys.fmt(f),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::MachineKeys;

    /// One board's device keys (as a board crate defines them).
    #[derive(Debug, Clone, PartialEq, Eq, Default)]
    struct CoilKeys {
        coils: Option<u8>,
    }

    /// Another board's.
    #[derive(Debug, Clone, PartialEq, Eq, Default)]
    struct VariantKeys {
        variant: u8,
    }

    #[test]
    fn machine_keys_hold_any_board_s_struct_and_compare_by_value() {
        let a = MachineKeys::new(CoilKeys { coils: Some(2) });
        assert_eq!(a.get::<CoilKeys>().and_then(|k| k.coils), Some(2));
        assert!(a.get::<VariantKeys>().is_none(), "another board's type");
        assert_eq!(a, a.clone());
        assert_ne!(a, MachineKeys::new(CoilKeys::default()));
        assert_ne!(a, MachineKeys::new(VariantKeys::default()));
        assert_ne!(a, MachineKeys::PLAIN);
        assert_eq!(MachineKeys::PLAIN, MachineKeys::default());
        assert_eq!(
            MachineKeys::PLAIN.get_or_default::<CoilKeys>(),
            CoilKeys::default()
        );
        assert_eq!(
            MachineKeys::new(VariantKeys { variant: 1 })
                .get::<VariantKeys>()
                .map(|k| k.variant),
            Some(1)
        );
    }
}
