//! A global allocator that counts the allocations of chosen stretches of one thread's
//! work: the proof that a real-time path allocates nothing. A test binary installs it with
//! `#[global_allocator] static GLOBAL: CountingAllocator = CountingAllocator;` and wraps the
//! work to count in [`counting`] or [`counted`]; other threads (simulated boards, the
//! harness) and the rest of the test are not counted.
#![allow(unsafe_code)] // a GlobalAlloc is an unsafe trait; every call is forwarded unchanged

use core::cell::Cell;
use std::alloc::{GlobalAlloc, Layout, System};

/// The system allocator, counting what [`counting`] asks it to.
#[derive(Debug, Clone, Copy, Default)]
pub struct CountingAllocator;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn note_allocation() {
    let _ = COUNTING.try_with(|counting| {
        if counting.get() {
            let _ = ALLOCATIONS.try_with(|count| count.set(count.get() + 1));
        }
    });
}

// SAFETY: every call is forwarded unchanged to the system allocator; the only addition is
// a thread-local counter that does not allocate.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note_allocation();
        // SAFETY: same contract as our caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as our caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note_allocation();
        // SAFETY: same contract as our caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Allocations counted on this thread so far.
pub fn allocations() -> u64 {
    ALLOCATIONS.with(Cell::get)
}

/// Runs `work`, counting the allocations this thread makes in it (see [`allocations`]).
pub fn counting<T>(work: impl FnOnce() -> T) -> T {
    COUNTING.with(|c| c.set(true));
    let result = work();
    COUNTING.with(|c| c.set(false));
    result
}

/// Runs `work`; its result and the allocations this thread made in it.
pub fn counted<T>(work: impl FnOnce() -> T) -> (T, u64) {
    let before = allocations();
    let result = counting(work);
    (result, allocations() - before)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[global_allocator]
    static GLOBAL: CountingAllocator = CountingAllocator;

    #[test]
    fn the_work_counted_is_the_work_wrapped_on_this_thread() {
        let (bytes, count) = counted(|| Vec::<u8>::with_capacity(64));
        assert_eq!(count, 1, "one allocation in the work");
        let (sum, count) = counted(|| bytes.capacity() + 1);
        assert_eq!(
            (sum >= 65, count),
            (true, 0),
            "none in work that allocates nothing"
        );
        // Outside the work, and on another thread inside it, nothing is counted.
        let before = allocations();
        let outside = std::hint::black_box(Vec::<u8>::with_capacity(16));
        let ((), count) = counted(|| {
            std::thread::spawn(|| drop(vec![0u8; 16]))
                .join()
                .expect("joined");
        });
        assert_eq!(allocations() - before, count);
        drop((bytes, outside));
    }
}
