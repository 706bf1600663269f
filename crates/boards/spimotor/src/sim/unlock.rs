//! The address-change unlock sequence (ports 0xf1, 0xf2, 0xf0).
//!
//! docs/ARCHITECTURE.md: write 0x55 to 0xf1, then 0xaa to 0xf2, then the new address to 0xf0. The
//! three writes must be the next three transactions addressed to the board: anything else
//! addressed to it in between (another write, a read, a malformed transaction, a wrong key)
//! aborts the sequence, and 0xf0 outside the sequence is ignored. Transactions to other
//! addresses are never seen by the board, so they do not abort it. A fresh 0x55 to 0xf1
//! always (re)starts the sequence.

use spimotor::{Address, Write};

/// How far the unlock sequence has got.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum UnlockStage {
    /// No unlock in progress: a write to 0xf0 is ignored.
    #[default]
    Locked,
    /// 0x55 was written to 0xf1.
    Started,
    /// 0xaa was written to 0xf2 right after: the next write to 0xf0 sets the address.
    Unlocked,
}

impl UnlockStage {
    /// The stage after a transaction addressed to the board (`None`: anything that is not a
    /// well-formed write), and the new address when the sequence completes.
    pub const fn next(self, write: Option<&Write>) -> (Self, Option<Address>) {
        match (self, write) {
            (_, Some(Write::UnlockAddress1)) => (Self::Started, None),
            (Self::Started, Some(Write::UnlockAddress2)) => (Self::Unlocked, None),
            (Self::Unlocked, Some(Write::ChangeAddress(address))) => (Self::Locked, Some(*address)),
            _ => (Self::Locked, None),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The addresses the sequence of transactions sets, in order.
    fn run(writes: &[Option<Write>]) -> Vec<Address> {
        let mut stage = UnlockStage::Locked;
        let mut changed = Vec::new();
        for w in writes {
            let (next, address) = stage.next(w.as_ref());
            stage = next;
            changed.extend(address);
        }
        changed
    }

    #[test]
    fn only_the_exact_sequence_changes_the_address() {
        let new = Address::new(0x92).unwrap();
        let change = Some(Write::ChangeAddress(new));
        let one = Some(Write::UnlockAddress1);
        let two = Some(Write::UnlockAddress2);
        assert_eq!(run(&[one, two, change]), [new]);
        assert_eq!(run(&[one, one, two, change]), [new]);
        assert_eq!(run(&[two, one, two, change]), [new]);
        assert_eq!(run(&[change]), []);
        assert_eq!(run(&[one, change]), []);
        assert_eq!(run(&[two, change]), []);
        assert_eq!(run(&[one, two, two, change]), []);
        assert_eq!(run(&[one, None, two, change]), []);
        assert_eq!(run(&[one, two, None, change]), []);
        let other = Some(Write::StepperIntensity(1));
        assert_eq!(run(&[one, two, other, change]), []);
        // Used once: the next 0xf0 needs a new sequence.
        assert_eq!(run(&[one, two, change, change]), [new]);
        assert_eq!(run(&[one, two, change, one, two, change]), [new, new]);
    }
}
