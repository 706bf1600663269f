#![no_main]
//! The CAN command cache (manual 6.2: 16 commands, about 2 ms each) under any sequence of
//! arrivals and polls: each input byte pair is (time step in 0.1 ms, operation). Nothing
//! panics, no more than 16 commands ever wait, every accepted command comes out once, in
//! arrival order, at least 2 ms after the one before.

use core::time::Duration;

use libfuzzer_sys::fuzz_target;
use tmcpack::{CAN_CACHE_COMMANDS, CAN_COMMAND_TIME, CanCache};

fuzz_target!(|data: &[u8]| {
    let mut cache = CanCache::<u32>::new();
    let mut now = Duration::ZERO;
    let mut next = 0u32;
    let mut accepted = std::collections::VecDeque::new();
    let mut last_done: Option<Duration> = None;
    for pair in data.chunks(2) {
        let step = u64::from(pair[0]) * 100;
        now += Duration::from_micros(step);
        let op = pair.get(1).copied().unwrap_or(0);
        if op & 1 == 0 {
            while let Some((done, item)) = cache.pop_done(now) {
                assert!(done <= now);
                assert_eq!(accepted.pop_front(), Some(item));
                if let Some(before) = last_done {
                    assert!(done >= before + CAN_COMMAND_TIME);
                }
                last_done = Some(done);
            }
            let full = cache.waiting(now) >= CAN_CACHE_COMMANDS;
            match cache.push(now, next) {
                Ok(done) => {
                    assert!(!full);
                    assert!(done >= now + CAN_COMMAND_TIME);
                    accepted.push_back(next);
                }
                Err(item) => {
                    assert!(full);
                    assert_eq!(item, next);
                }
            }
            next += 1;
        }
        assert!(cache.waiting(now) <= CAN_CACHE_COMMANDS);
        assert!(cache.room_at(now) >= now);
    }
});
