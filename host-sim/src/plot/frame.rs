//! Plot panels: a data box mapped onto pixels, with a grid, 1-2-5 tick
//! labels and axis titles, and polylines drawn in it.

use std::fmt::Write as _;

/// A 1-2-5 tick step giving about `n` ticks over `span`.
fn nice_step(span: f64, n: f64) -> f64 {
    let raw = (span / n).max(1e-9);
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    let m = if f <= 1.0 {
        1.0
    } else if f <= 2.0 {
        2.0
    } else if f <= 5.0 {
        5.0
    } else {
        10.0
    };
    m * mag
}

fn ticks(lo: f64, hi: f64, step: f64) -> (Vec<f64>, usize) {
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10()).ceil() as usize
    };
    let mut v = Vec::new();
    let mut t = (lo / step).ceil() * step;
    while t <= hi + step * 1e-6 && v.len() < 100 {
        v.push(if t.abs() < step * 1e-6 { 0.0 } else { t });
        t += step;
    }
    (v, decimals)
}

/// A panel: data box [x0, x1] × [y0, y1] mapped onto pixels.
pub(super) struct Frame {
    pub left: f64,
    pub top: f64,
    pub w: f64,
    pub h: f64,
    pub x: (f64, f64),
    pub y: (f64, f64),
    /// Same tick spacing on both axes (the equal-aspect XY view).
    pub equal: bool,
}

impl Frame {
    pub fn px(&self, x: f64) -> f64 {
        self.left + (x - self.x.0) / (self.x.1 - self.x.0) * self.w
    }
    pub fn py(&self, y: f64) -> f64 {
        self.top + self.h - (y - self.y.0) / (self.y.1 - self.y.0) * self.h
    }

    /// Background, grid, tick labels and axis titles.
    pub fn axes(&self, s: &mut String, xlabel: &str, ylabel: &str) {
        let (l, t, r, b) = (self.left, self.top, self.left + self.w, self.top + self.h);
        let _ = writeln!(
            s,
            r##"<rect x="{l:.1}" y="{t:.1}" width="{:.1}" height="{:.1}" fill="#fcfcfc" stroke="none"/>"##,
            self.w, self.h
        );
        let xstep = nice_step(self.x.1 - self.x.0, self.w / 90.0);
        let (xt, xd) = ticks(self.x.0, self.x.1, xstep);
        for v in xt {
            let x = self.px(v);
            let _ = writeln!(
                s,
                r#"<line class="grid" x1="{x:.1}" y1="{t:.1}" x2="{x:.1}" y2="{b:.1}"/>"#
            );
            let _ = writeln!(
                s,
                r#"<text x="{x:.1}" y="{:.1}" text-anchor="middle">{v:.xd$}</text>"#,
                b + 16.0
            );
        }
        let ystep = if self.equal {
            xstep
        } else {
            nice_step(self.y.1 - self.y.0, (self.h / 35.0).max(2.5))
        };
        let (yt, yd) = ticks(self.y.0, self.y.1, ystep);
        for v in yt {
            let y = self.py(v);
            let _ = writeln!(
                s,
                r#"<line class="grid" x1="{l:.1}" y1="{y:.1}" x2="{r:.1}" y2="{y:.1}"/>"#
            );
            let _ = writeln!(
                s,
                r#"<text x="{:.1}" y="{:.1}" text-anchor="end">{v:.yd$}</text>"#,
                l - 6.0,
                y + 4.0
            );
        }
        let _ = writeln!(
            s,
            r##"<rect x="{l:.1}" y="{t:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#777" stroke-width="1"/>"##,
            self.w, self.h
        );
        let _ = writeln!(
            s,
            r#"<text class="lab" x="{:.1}" y="{:.1}" text-anchor="middle">{xlabel}</text>"#,
            l + self.w / 2.0,
            b + 36.0
        );
        let (cx, cy) = (l - 56.0, t + self.h / 2.0);
        let _ = writeln!(
            s,
            r#"<text class="lab" x="{cx:.1}" y="{cy:.1}" text-anchor="middle" transform="rotate(-90 {cx:.1} {cy:.1})">{ylabel}</text>"#
        );
    }

    pub fn clip(&self, s: &mut String, id: &str) {
        let _ = writeln!(
            s,
            r#"<clipPath id="{id}"><rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}"/></clipPath>"#,
            self.left, self.top, self.w, self.h
        );
    }
}

pub(super) fn polyline(
    s: &mut String,
    class: &str,
    f: &Frame,
    pts: impl Iterator<Item = [f64; 2]>,
) {
    s.push_str(r#"<polyline class=""#);
    s.push_str(class);
    s.push_str(r#"" points=""#);
    for q in pts {
        let _ = write!(s, "{:.1},{:.1} ", f.px(q[0]), f.py(q[1]));
    }
    s.push_str("\"/>\n");
}
