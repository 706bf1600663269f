//! The priority of the threads that play boards ([`crate::pty_board`],
//! [`crate::socket_board`]). A real board has a processor of its own: it takes a request
//! as its bytes arrive and answers on its own clock, however busy the host is. A thread
//! of the test process that plays it is not so lucky: starved for a few milliseconds on a
//! loaded machine (a CI runner, every test of a binary at once), it reads a request late,
//! answers it late, and then takes the host's next request for one that interlaced with
//! its answer — a fault of the harness that the server under test never made. So the board
//! threads ask for SCHED_FIFO (as `motionctl bench --rt-priority` does for its boards),
//! or failing that the highest nice value allowed; each sleeps between bytes, so the CPU
//! they take is small.
#![allow(unsafe_code)] // the test reads the policy back: sched_getscheduler and getpriority have no safe wrapper in nix; see the SAFETY notes

/// The SCHED_FIFO priority asked for: above every normal thread, below anything a
/// real-time configuration of the server would use.
const FIFO_PRIORITY: u8 = 10;

/// The nice value asked for when SCHED_FIFO is refused.
const NICE: i32 = -10;

/// What the calling thread got.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoardPriority {
    /// SCHED_FIFO at this priority.
    Fifo(i32),
    /// The normal policy at this nice value.
    Nice(i32),
    /// Neither was allowed (no CAP_SYS_NICE, no rtprio or nice limit): the normal policy.
    Normal,
}

/// Raises the calling thread's priority as far as allowed; says how far.
pub fn raise() -> BoardPriority {
    if motion_rt::set_fifo(FIFO_PRIORITY).is_ok() {
        return BoardPriority::Fifo(i32::from(FIFO_PRIORITY));
    }
    if motion_rt::set_nice(NICE).is_ok() {
        return BoardPriority::Nice(NICE);
    }
    BoardPriority::Normal
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The calling thread's policy and nice value, as the kernel has them.
    fn policy_and_nice() -> (i32, i32) {
        // SAFETY: pid 0 is the calling thread; no pointer is passed.
        let policy = unsafe { libc::sched_getscheduler(0) };
        // SAFETY: gettid has no arguments and cannot fail.
        let tid = unsafe { libc::gettid() };
        // SAFETY: plain integer arguments (getpriority's -1 is also a valid nice value, so
        // errno is not consulted: the thread exists).
        let nice = unsafe { libc::getpriority(libc::PRIO_PROCESS, tid as libc::id_t) };
        (policy, nice)
    }

    #[test]
    fn a_board_thread_gets_what_it_says_it_got() {
        let (got, (policy, nice)) = std::thread::spawn(|| (raise(), policy_and_nice()))
            .join()
            .expect("the thread ran");
        match got {
            BoardPriority::Fifo(_) => assert_eq!(policy, libc::SCHED_FIFO),
            BoardPriority::Nice(value) => {
                assert_eq!((policy, nice), (libc::SCHED_OTHER, value));
            }
            BoardPriority::Normal => assert_eq!(policy, libc::SCHED_OTHER),
        }
        // SAFETY: geteuid has no arguments and cannot fail.
        if unsafe { libc::geteuid() } == 0 {
            // Root (CAP_SYS_NICE): the first choice.
            assert_eq!(got, BoardPriority::Fifo(i32::from(FIFO_PRIORITY)));
        }
        // The thread that asked, not the process: the test thread keeps its policy.
        assert_eq!(policy_and_nice().0, libc::SCHED_OTHER);
    }
}
