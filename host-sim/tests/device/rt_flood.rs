//! Realtime commands under an output flood (issue 13, item 4): the host
//! stops reading while the device has a ring's worth of replies queued;
//! a feed hold, cycle start and override still act within a millisecond,
//! a status query waits until its reply fits, and no reply is cut.

use burin::controller::TX_RING;
use burin::executor::State;
use host_sim::device_sim::VirtualDevice;
use host_sim::record::Discard;

use crate::rig;

fn ms(dev: &VirtualDevice, n: u64) -> u64 {
    dev.sim.now() + u64::from(dev.sim.tick_hz()) / 1000 * n
}

fn state(dev: &VirtualDevice) -> State {
    dev.sim.machine.state(&dev.sim.rt)
}

#[test]
fn hold_acts_within_a_millisecond_while_replies_back_up() {
    let cfg = rig::origin();
    let mut rec = Discard;
    let mut dev = VirtualDevice::new(&cfg, &mut rec);
    dev.tx.1 = Some(TX_RING);
    dev.take_output();
    assert_eq!(dev.receive(b"G1 X200 F3000\n"), 14);
    let t = ms(&dev, 200);
    dev.advance_to(t);
    assert_eq!(state(&dev), State::Run);
    dev.take_output();
    // The host stops reading: `$$` listings fill the ring past the
    // session's headroom, and the rest of the input waits.
    for _ in 0..4 {
        assert_eq!(dev.receive(b"$$\n"), 3);
    }
    let t = ms(&dev, 5);
    dev.advance_to(t);
    let queued = dev.tx.0.len();
    assert!(
        TX_RING - queued < burin::controller::TX_HEADROOM,
        "ring not backed up: {queued} bytes"
    );
    assert!(dev.rx_pending() > 0, "input should wait for reply room");
    // Realtime bytes act anyway, within a millisecond.
    assert_eq!(dev.receive(&[0x91, b'!']), 2);
    let t = ms(&dev, 1);
    dev.advance_to(t);
    assert!(dev.sim.rt.hold_requested(), "feed hold did not act");
    assert_eq!(dev.sim.rt.feed_override(), 110, "override did not act");
    assert_eq!(dev.tx.0.len(), queued, "silent commands wrote a reply");
    // Held to a stop, still unread: the position does not move.
    let t = ms(&dev, 1500);
    dev.advance_to(t);
    assert_eq!(state(&dev), State::Hold);
    assert!(dev.sim.rt.stepper_idle());
    let held = dev.position_steps();
    // `?` is answered while its reply fits; then it waits, and is
    // answered once the host reads again.
    let statuses =
        |dev: &VirtualDevice| String::from_utf8_lossy(&dev.tx.0).matches("<Hold").count();
    let mut asked = 0;
    while TX_RING - dev.tx.0.len() >= burin::session::RT_REPLY_ROOM {
        assert_eq!(dev.receive(b"?"), 1);
        asked += 1;
        let t = ms(&dev, 1);
        dev.advance_to(t);
        assert_eq!(statuses(&dev), asked, "a status was not answered at once");
        assert!(asked < 20, "the ring never fills");
    }
    assert_eq!(dev.receive(b"?"), 1);
    let t = ms(&dev, 5);
    dev.advance_to(t);
    assert_eq!(statuses(&dev), asked, "status written into a full ring");
    // Cycle start resumes, still with the host not reading.
    assert_eq!(dev.receive(b"~"), 1);
    let t = ms(&dev, 1);
    dev.advance_to(t);
    assert!(!dev.sim.rt.hold_requested(), "cycle start did not act");
    let t = ms(&dev, 50);
    dev.advance_to(t);
    assert_ne!(dev.position_steps(), held, "did not resume");
    // The host reads again: every listing whole, the status answered.
    let mut out = Vec::new();
    for _ in 0..50 {
        out.extend(dev.take_output());
        let t = ms(&dev, 5);
        dev.advance_to(t);
    }
    out.extend(dev.take_output());
    let text = String::from_utf8_lossy(&out);
    assert_eq!(text.matches("$0=").count(), 4, "{text}");
    assert_eq!(text.matches("$132=").count(), 4, "a listing was cut");
    // The waiting `?` is answered once read (by then the job runs again).
    assert_eq!(text.matches("|MPos:").count(), asked + 1, "{text}");
}
