//! Thin wrapper: the checks live in `host_sim::fuzz::protocol_frames` so the stable
//! regression test (`host-sim/tests/device/fuzz_regressions.rs`) runs them too.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| host_sim::fuzz::protocol_frames(data));
