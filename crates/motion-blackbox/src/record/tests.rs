use motion_ipc::{ClientId, CommandKind, CommandRequest, GroupPath};

use super::*;

fn sparse<T: Fields>(value: &T) -> Vec<u8> {
    let mut bytes = vec![0u8; sparse_len(value)];
    let mut writer = SplitWriter::new(&mut bytes, &mut []);
    put_sparse(&mut writer, value);
    bytes
}

#[test]
fn a_request_comes_back_bit_for_bit_nan_and_negative_zero_included() {
    let mut request = CommandRequest::new(ClientId { lo: 3, hi: 9 }, 41, 2, CommandKind::Position);
    request.values = [f64::NAN, -0.0, 1.5];
    let bytes = sparse(&request);
    let back: CommandRequest = get_sparse(&bytes).expect("decodes");
    assert_eq!(back.values[0].to_bits(), f64::NAN.to_bits());
    assert_eq!(back.values[1].to_bits(), (-0.0f64).to_bits());
    assert_eq!((back.sequence, back.axis, back.kind), (41, 2, request.kind));
    assert_eq!(back.client, request.client);
}

/// Runs `test` on a thread with a stack for 400 KiB payloads by value.
fn with_big_stack(test: impl FnOnce() + Send + 'static) {
    std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(test)
        .expect("a thread")
        .join()
        .expect("the test passed");
}

#[test]
fn a_line_path_of_400_kib_takes_a_few_entries() {
    with_big_stack(a_line_path);
}

fn a_line_path() {
    let mut path = Box::new(GroupPath::EMPTY);
    path.point_count = 1;
    path.axis_count = 3;
    path.positions[..3].copy_from_slice(&[1.0, 2.0, 3.0]);
    let bytes = sparse(&*path);
    assert!(bytes.len() < 200, "{} bytes", bytes.len());
    let back: GroupPath = get_sparse(&bytes).expect("decodes");
    assert_eq!(back.positions[..4], [1.0, 2.0, 3.0, 0.0]);
    assert_eq!(back.schema_version, path.schema_version);
}

#[test]
fn sparse_bytes_out_of_order_or_cut_are_refused() {
    let request = CommandRequest::new(ClientId { lo: 1, hi: 0 }, 5, 1, CommandKind::Stop);
    let bytes = sparse(&request);
    assert!(get_sparse::<CommandRequest>(&bytes[..bytes.len() - 1]).is_none());
    let mut swapped = bytes.clone();
    let (a, b) = swapped.split_at_mut(12);
    a.swap_with_slice(&mut b[..12]);
    assert!(get_sparse::<CommandRequest>(&swapped).is_none());
    // An entry past the payload's end is refused too.
    let mut past = bytes;
    past.extend_from_slice(&10_000u32.to_le_bytes());
    past.extend_from_slice(&1u64.to_le_bytes());
    assert!(get_sparse::<CommandRequest>(&past).is_none());
}

#[test]
fn records_split_across_the_ring_end_read_back_in_order() {
    let mut first = [0u8; 5];
    let mut second = [0u8; 11];
    let mut writer = SplitWriter::new(&mut first, &mut second);
    put_header(&mut writer, Kind::LinkTx, 2, 3);
    writer.put(&[7, 8, 9]);
    put_header(&mut writer, Kind::Step, 0, 0);
    assert_eq!(writer.written(), 15);
    let mut joined = first.to_vec();
    joined.extend_from_slice(&second[..10]);
    let read: Vec<_> = records(&joined)
        .collect::<Result<_, _>>()
        .expect("whole records");
    assert_eq!(read.len(), 2);
    assert_eq!(
        (read[0].kind, read[0].link, read[0].payload),
        (Kind::LinkTx, 2, &[7, 8, 9][..])
    );
    assert_eq!(read[1].kind, Kind::Step);
}

#[test]
fn garbage_is_an_error_not_a_panic() {
    assert!(matches!(
        records(&[0xee, 0, 0, 0, 0, 0]).next(),
        Some(Err(JournalError::UnknownKind { kind: 0xee, .. }))
    ));
    assert!(matches!(
        records(&[Kind::LinkRx as u8, 0, 200, 0, 0, 0, 1, 2]).next(),
        Some(Err(JournalError::Truncated {
            len: 200,
            left: 2,
            ..
        }))
    ));
    // Every byte string ends the iterator without a panic.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for _ in 0..2000 {
        let len = (state % 64) as usize;
        let bytes: Vec<u8> = (0..len)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                state as u8
            })
            .collect();
        let _ = records(&bytes).count();
        let _ = get_sparse::<CommandRequest>(&bytes);
    }
}
