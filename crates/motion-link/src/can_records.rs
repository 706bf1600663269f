//! The write side every CAN link shares: the bytes a driver writes are 16-byte CAN records
//! (`motion_base::CanRecord`), and a record may come in parts over several writes; each
//! whole record goes out as one frame.

use core::time::Duration;

use motion_base::CAN_RECORD_LEN;

use crate::error::LinkError;

/// A CAN link's record being assembled, and how it sends a whole one.
pub(crate) trait RecordSender {
    /// The record being assembled and how many of its bytes are there.
    fn pending(&mut self) -> (&mut [u8; CAN_RECORD_LEN], &mut usize);
    /// Sends the pending record (whole): `Ok(false)` when the transmit queue is full (not
    /// sent).
    fn send_pending(&mut self, now: Duration) -> Result<bool, LinkError>;
    /// Counts `bytes` written.
    fn count_out(&mut self, bytes: usize);
}

/// Takes `bytes` up to whole records, sending each; a record's first bytes are kept until
/// the rest comes. Stops (returning what it took) at a full transmit queue: the bytes of
/// the record not sent are not taken.
pub(crate) fn write_records<S: RecordSender>(
    link: &mut S,
    now: Duration,
    bytes: &[u8],
) -> Result<usize, LinkError> {
    let mut taken = 0;
    while taken < bytes.len() {
        let rest = bytes.get(taken..).unwrap_or_default();
        let (record, len) = link.pending();
        let saved = *len;
        let want = CAN_RECORD_LEN - saved;
        if rest.len() < want {
            // Part of a record: kept until the rest comes.
            if let Some(slot) = record.get_mut(saved..saved + rest.len()) {
                slot.copy_from_slice(rest);
            }
            *len += rest.len();
            taken += rest.len();
            break;
        }
        if let (Some(slot), Some(part)) = (record.get_mut(saved..), rest.get(..want)) {
            slot.copy_from_slice(part);
        }
        *len = CAN_RECORD_LEN;
        match link.send_pending(now) {
            Ok(true) => taken += want,
            Ok(false) => {
                *link.pending().1 = saved;
                break;
            }
            Err(e) => {
                link.count_out(taken);
                return Err(e);
            }
        }
    }
    link.count_out(taken);
    Ok(taken)
}
