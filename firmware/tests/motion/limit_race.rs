//! A limit interrupt that preempts the planner task in the middle of a
//! segment fill: nothing that fill prepared from the old plan may run.

use burin::command::{Command, Feed};
use burin::executor::Machine;
use burin::realtime::Realtime;
use burin::settings::Settings;
use burin::stepper::sink::SegmentSink;
use burin::stepper::{Segment, StepConfig, Stepper, Switches};

/// A queue whose `after`-th push is where the "interrupt" lands.
struct Preempted<'a> {
    rt: &'a Realtime,
    queue: Vec<Segment>,
    after: usize,
}

impl SegmentSink for Preempted<'_> {
    fn push(&mut self, s: Segment) -> Result<(), Segment> {
        self.queue.push(s);
        if self.queue.len() == self.after {
            self.rt.hard_limit(0b001);
        }
        Ok(())
    }
    fn is_full(&self) -> bool {
        self.queue.len() >= 12
    }
    fn is_empty(&self) -> bool {
        self.queue.is_empty()
    }
    fn len(&self) -> usize {
        self.queue.len()
    }
}

fn long_move(rt: &Realtime) -> Machine<16> {
    let mut m = Machine::<16>::new(Settings::default(), 1_000_000);
    let cmd = Command::Line {
        end: burin::pad([100.0, 0.0, 0.0, 0.0]),
        feed: Feed::PerMin(600.0),
    };
    m.submit(rt, &cmd, 1, &mut |_| {}).expect("submit");
    m
}

#[test]
fn segments_of_a_fill_preempted_by_a_limit_never_step() {
    for after in [1, 2, 5] {
        let rt = Realtime::new();
        let mut m = long_move(&rt);
        let mut sink = Preempted {
            rt: &rt,
            queue: Vec::new(),
            after,
        };
        m.poll(&rt, &mut sink, Switches::default(), &mut |_| {});
        assert!(sink.queue.len() >= after, "the fill went on past the trip");
        let mut st = Stepper::new(StepConfig::new(&Settings::default(), 1_000_000));
        let mut queue = sink.queue.into_iter();
        let ev = st.on_event(&rt, &mut || queue.next(), Switches::default);
        assert_eq!(
            (ev.ticks, ev.step_mask),
            (0, 0),
            "after {after}: a step ran"
        );
        assert_eq!(rt.position(), [0; burin::AXES]);
    }
}

#[test]
fn no_fill_once_a_hard_limit_tripped() {
    let rt = Realtime::new();
    let mut m = long_move(&rt);
    rt.hard_limit(0b010);
    let mut sink = Preempted {
        rt: &rt,
        queue: Vec::new(),
        after: usize::MAX,
    };
    m.poll(&rt, &mut sink, Switches::default(), &mut |_| {});
    assert!(
        sink.queue.is_empty(),
        "{} segments prepared",
        sink.queue.len()
    );
}
