//! Reply decoder under a layout taken from the first five input bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use qq2drv::{
    DataMask, MotionLayout, PositionLayout, PositionSize, Reply, ReplyLayout, StreamConfig,
};

fuzz_target!(|data: &[u8]| {
    let Some((head, packet)) = data.split_first_chunk::<5>() else {
        return;
    };
    let masks = [
        DataMask(head[0]),
        DataMask(head[1]),
        DataMask(head[2]),
        DataMask(head[3]),
    ];
    let layout = ReplyLayout {
        motion: MotionLayout {
            data_masks: masks,
            stream_config: StreamConfig(head[4]),
        },
        position: PositionLayout([0, 2, 4, 6].map(|s| PositionSize::from_bits(head[4] >> s))),
    };
    if let Ok(reply) = Reply::parse(packet, &layout) {
        let mut buf = [0u8; 255];
        let n = reply.encode(&mut buf).expect("a decoded reply re-encodes");
        assert_eq!(&buf[..n], packet);
    }
});
