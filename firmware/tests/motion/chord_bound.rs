//! A move made of many chords that each round to no step (a helix of
//! 65 536 turns on a radius far under one step) is planned a bounded piece
//! per call: the executor's task pass stays short, so the device keeps
//! answering while it works through it, and the job still ends where it
//! should.

use burin::command::{Arc, ArcDir, Command, Feed, Plane};
use burin::executor::{Machine, Note, CHORDS_PER_CALL};
use burin::realtime::Realtime;
use burin::settings::Settings;
use burin::stepper::{Segment, Stepper, Switches};
use heapless::spsc::Queue;

#[test]
fn chords_under_a_step_are_planned_a_bounded_piece_per_call() {
    let rt = Realtime::new();
    let mut m: Machine<64> = Machine::new(Settings::default(), 96_000_000);
    let mut st = Stepper::new(m.step_config());
    let mut q: Queue<Segment, 16> = Queue::new();
    let helix = Command::Arc(Arc {
        end: burin::pad([0.0, 0.0, 0.0, 0.0]),
        center: [0.001, 0.0],
        plane: Plane::XY,
        dir: ArcDir::Ccw,
        turns: u16::MAX,
        feed: Feed::PerMin(1000.0),
    });
    let mut chords = 0u32;
    let mut count = |n: Note| {
        if let Note::Path { .. } = n {
            chords += 1;
        }
    };
    m.submit(&rt, &helix, 1, &mut count).expect("accepted");
    let mut total = std::mem::take(&mut chords) as u64;
    assert!(
        total <= u64::from(CHORDS_PER_CALL),
        "submit planned {total}"
    );
    let mut polls = 0u32;
    while !m.ready() || !m.motion.planner().is_empty() || !q.is_empty() || !rt.stepper_idle() {
        let mut count = |n: Note| {
            if let Note::Path { .. } = n {
                chords += 1;
            }
        };
        m.poll(&rt, &mut q, Switches::default(), &mut count);
        assert!(
            chords <= CHORDS_PER_CALL,
            "one poll planned {chords} chords"
        );
        total += u64::from(std::mem::take(&mut chords));
        let (mut pop, mut left) = (|| q.dequeue(), 10_000);
        while st.on_event(&rt, &mut pop, Switches::default).ticks > 0 && left > 0 {
            left -= 1;
        }
        polls += 1;
        assert!(polls < 100_000, "never finished ({total} chords)");
    }
    assert!(total > 100_000, "only {total} chords");
    assert!(polls as u64 >= total / u64::from(CHORDS_PER_CALL));
    assert_eq!(rt.position(), [0; burin::AXES]);
}
