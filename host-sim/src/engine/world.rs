//! The physical machine around the steppers: where the motors really are
//! (counted from the step pulses and the direction pins' levels,
//! independent of what the core believes), where the tool is behind the
//! machine's mechanical slack, and which switches the motors' position
//! closes, as pin levels through the machine's [`Wiring`].

use burin::stepper::Switches;
use burin::AXES;

use crate::config::{MachineConfig, Wiring};

#[derive(Clone, Copy, Debug)]
struct Limit {
    /// Trip point in world steps.
    trip: i64,
    /// Steps back off the trip point at which it opens again.
    hysteresis: i64,
    /// +1: closes at or above `trip`; -1: at or below.
    sense: i64,
    closed: bool,
}

/// World position and switch states.
#[derive(Clone, Debug)]
pub struct World {
    /// Physical position in steps from world zero.
    pub steps: [i64; AXES],
    /// The tool, in steps from world zero: it follows the motor within a
    /// dead band of the axis's slack (`MachineConfig::slack_mm`), `steps -
    /// tool` kept in `band[i]`.
    tool: [f64; AXES],
    band: [(f64, f64); AXES],
    slack: bool,
    limits: [Option<Limit>; AXES],
    probe: Option<(usize, i64, i64)>,
    wiring: Wiring,
    pins: Switches,
    watched: u8,
}

impl World {
    pub fn new(cfg: &MachineConfig) -> Self {
        let s = &cfg.settings;
        let spm = |i: usize| s.axes[i].steps_per_mm as f64;
        let steps =
            std::array::from_fn(|i| (cfg.start_position_mm[i] as f64 * spm(i)).round() as i64);
        let limits = std::array::from_fn(|i| {
            cfg.limits[i].map(|l| Limit {
                trip: (l.trip_mm as f64 * spm(i)).round() as i64,
                hysteresis: (l.hysteresis_mm.max(0.0) as f64 * spm(i)).round() as i64,
                sense: if s.homing_dir_invert & (1 << i) != 0 {
                    -1
                } else {
                    1
                },
                closed: false,
            })
        });
        let probe = cfg.probe.filter(|p| p.axis < AXES).map(|p| {
            let sense = if p.towards_negative { -1 } else { 1 };
            (
                p.axis,
                (p.trip_mm as f64 * spm(p.axis)).round() as i64,
                sense,
            )
        });
        let mut watched = 0u8;
        for (i, l) in limits.iter().enumerate() {
            if l.is_some() {
                watched |= 1 << i;
            }
        }
        if let Some((a, _, _)) = probe {
            watched |= 1 << a;
        }
        // Taken up towards the homing direction at power-up (the state the
        // firmware's compensation assumes, `motion::Pipeline`): moving
        // that way moves the tool at once, the other way first crosses
        // the slack.
        let band = std::array::from_fn(|i| {
            let b = f64::from(cfg.slack_mm[i].max(0.0)) * spm(i);
            if s.homing_dir_invert & (1 << i) != 0 {
                (0.0, b)
            } else {
                (-b, 0.0)
            }
        });
        let mut w = World {
            steps,
            tool: steps.map(|v| v as f64),
            band,
            slack: cfg.slack_mm.iter().any(|&b| b > 0.0),
            limits,
            probe,
            wiring: cfg.wiring.unwrap_or(Wiring::matching(s)),
            pins: Switches::default(),
            watched,
        };
        w.update();
        w
    }

    /// Moves the probe surface by `steps` along its axis (a test's way to
    /// put a longer or shorter tool in the spindle: a tool-setter then
    /// trips that much earlier or later).
    pub fn shift_probe(&mut self, steps: i64) {
        if let Some((_, trip, _)) = &mut self.probe {
            *trip += steps;
        }
        self.update();
    }

    /// Where the tool is, mm from world zero (the machine's coordinates
    /// while the firmware's position was set to the world's, as the
    /// start position does).
    pub fn tool_mm(&self, steps_per_mm: &[f32; AXES]) -> [f64; AXES] {
        std::array::from_fn(|i| {
            let t = if self.slack {
                self.tool[i]
            } else {
                self.steps[i] as f64
            };
            t / f64::from(steps_per_mm[i])
        })
    }

    /// Pin levels as the firmware reads them: a normally-closed switch
    /// reads active while open (the firmware's `$5`/`$6` must say so).
    pub fn switches(&self) -> Switches {
        self.pins
    }

    /// Apply one step event; `dir_pins`: the direction pins' levels (bit
    /// set: high), which turn each motor as it is wired.
    #[inline]
    pub fn step(&mut self, step_mask: u8, dir_pins: u8) {
        let negative = dir_pins ^ self.wiring.motors_reversed;
        for i in 0..AXES {
            if step_mask & (1 << i) != 0 {
                self.steps[i] += if negative & (1 << i) != 0 { -1 } else { 1 };
                if self.slack {
                    let (lo, hi) = self.band[i];
                    let m = self.steps[i] as f64;
                    self.tool[i] = self.tool[i].clamp(m - hi, m - lo);
                }
            }
        }
        if step_mask & self.watched != 0 {
            self.update();
        }
    }

    fn update(&mut self) {
        let mut limits = 0u8;
        for i in 0..AXES {
            if let Some(l) = &mut self.limits[i] {
                let x = self.steps[i] * l.sense;
                let t = l.trip * l.sense;
                if x >= t {
                    l.closed = true;
                } else if x < t - l.hysteresis {
                    l.closed = false;
                }
                if l.closed {
                    limits |= 1 << i;
                }
            }
        }
        let contact = self
            .probe
            .is_some_and(|(a, trip, sense)| self.steps[a] * sense >= trip * sense);
        self.pins = Switches {
            limits: limits ^ self.wiring.limits_nc,
            probe: contact ^ self.wiring.probe_nc,
        };
    }
}
