use crate::common;
use burin::command::{Command, Feed};
use common::*;
use host_sim::engine::Sim;

#[test]
fn single_line_exact() {
    let cfg = config();
    let mut rec = Collect::default();
    let mut sim = Sim::new(&cfg, &mut rec);
    sim.push_command(
        1,
        Command::Line {
            end: burin::pad([10.0, 5.0, -1.0, 0.0]),
            feed: Feed::PerMin(1000.0),
        },
    );
    sim.push_command(
        2,
        Command::Rapid {
            end: burin::pad([0.0, 0.0, 0.0, 0.0]),
        },
    );
    sim.run();
    let s = sim.summary(2, [0.0; burin::AXES]);
    drop(sim);
    println!("{s:?} events {}", rec.events.len());
    assert_eq!(s.final_position_steps, burin::pad([0, 0, 0, 0]));
    assert_eq!(s.steps, burin::pad([1600, 800, 800, 0]));
    let info = rec.info.clone().unwrap();
    println!("rate {}", check_max_rate(&info, &rec.events));
    let (dev, corners) = check_path(&info, [0.0; burin::AXES], &rec.path, &rec.events, 0.0);
    println!(
        "accel {}",
        check_max_accel(&info, &rec.events, &corners, 0.01)
    );
    check_pin_timing(&info, &rec.events);
    println!("path {dev}");
}
