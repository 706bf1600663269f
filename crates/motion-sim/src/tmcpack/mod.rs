//! Simulated tmcpack board (work in progress).
