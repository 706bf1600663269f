//! `motiond`, the real-time motion server.
//!
//! The server itself (config, links, tick thread, iceoryx2 services) is still being built;
//! until it lands this binary says honestly what exists and how to try it.
#![forbid(unsafe_code)]

fn main() {
    eprintln!(
        "motiond: the real-time server is not built yet (open issue: \
         \"motiond: the real-time server over iceoryx2\").\n\
         What exists today: sans-I/O codecs for the four boards, the link transports and \
         byte-exact board simulators.\n\
         Try a simulated board by hand: cargo run -p motion-sim -- --help"
    );
}
