//! Sessions recorded on `sim --pty` with `BURIN_PTY_TRACE` (see
//! `host_sim::pty`), replayed tick for tick: each once went wrong with a
//! real sender, and each must now end idle where its `# want-steps` line
//! says.

use host_sim::config::MachineConfig;
use host_sim::record::Discard;

fn replay(name: &str) {
    let path = format!("{}/tests/data/pty/{name}", env!("CARGO_MANIFEST_DIR"));
    let trace = std::fs::read_to_string(&path).expect("trace");
    let want: Vec<i32> = trace
        .lines()
        .find_map(|l| l.strip_prefix("# want-steps "))
        .expect("a # want-steps line")
        .split(',')
        .map(|v| v.trim().parse().expect("steps"))
        .collect();
    let cfg = MachineConfig::default();
    let mut rec = Discard;
    let (dev, out) = host_sim::pty::replay(&cfg, &mut rec, &trace).expect("replay");
    let text = String::from_utf8_lossy(&out);
    let tail = &text[text.len().saturating_sub(300)..];
    assert!(
        dev.idle(),
        "{name}: not idle at the end; last replies:\n{tail}"
    );
    // The trace names the axes it moves; the others stand at 0.
    let mut all = [0; burin::AXES];
    all[..want.len()].copy_from_slice(&want);
    assert_eq!(dev.position_steps(), all, "{name}: end position");
    assert!(!text.contains("error"), "{name}: {text}");
}

/// grbl-streamer held the first rapid just after it began: the hold ended
/// a fraction past a step at almost no speed, and that step was timed from
/// that speed: an 11 s wait, renewed for ever; after `~` the machine
/// reported Run and never moved (the CI senders check timed out).
#[test]
fn a_hold_ending_just_past_a_step_resumes() {
    replay("hold-ends-past-a-step.trace");
}
