mod common;
use common::*;
#[path = "motion_trace.rs"]
#[allow(dead_code)]
mod t;
#[test]
#[ignore]
fn dbg() {
    let cfg = config();
    let mut rec = Collect::default();
    let mut sim = host_sim::engine::Sim::new(&cfg, &mut rec);
    use burin::command::*;
    let cmds = vec![
        Command::Line { end: [50.0, 0.0, 0.0, 0.0], feed: Feed::PerMin(3000.0) },
        Command::Arc(Arc{end:[0.0, 0.0, 0.0, 0.0], center:[25.0, 0.0], plane:Plane::XY, dir:ArcDir::Ccw, turns:0, feed:Feed::PerMin(3000.0)}),
    ];
    for (i, c) in cmds.iter().enumerate() { sim.push_command(i as u32 + 1, c.clone()); }
    sim.input_at(134400000, host_sim::engine::Input::FeedHold);
    sim.input_at(192000000, host_sim::engine::Input::CycleStart);
    let mut last = 0;
    for _ in 0..6000 {
        let t = sim.now() + 96000;
        sim.run_until(t);
        let u = sim.rt.underruns();
        if u != last { println!("underrun at {}", sim.now() as f64 / 96e6); last = u; }
        if sim.now() > 96000000*5 { break; }
    }
    drop(sim);
    let hz = 96e6;
    for e in rec.events.iter().filter(|e| { let t = e.tick as f64 / hz; t > 1.3 && t < 1.6 }).step_by(20) {
        println!("{:.4} {:?}", e.tick as f64 / hz, e.pos);
    }
    for v in rec.velocity.iter().filter(|v| { let t = v.0 as f64 / hz; t > 1.3 && t < 1.6 }) { println!("v {:.4} {}", v.0 as f64/hz, v.1); }
}
