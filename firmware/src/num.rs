//! Decimal text to `f32` and back, without core's float text machinery.
//!
//! core's `f32::from_str` and float `Display` pull in about 30 KB of code
//! and tables (Eisel-Lemire with a 10 KB power-of-five table, Grisu, Dragon
//! and the exact formatter) to be correct for every possible input. G-code
//! and GRBL replies need much less: numbers without exponents, and replies
//! with a fixed number of decimals. This module does exactly that, in a few
//! hundred bytes, and says where it differs from core:
//!
//! - parsing is correctly rounded (one `f32` operation on exact operands
//!   for up to 7 significant digits and 10 decimals, every number a CAM
//!   program writes; 128-bit integer scaling beyond). Digits past the 19th
//!   significant one are dropped, so such a number may be 1 ulp off when it
//!   lies within 10^-18 (relative) of the midpoint of two floats;
//! - formatting prints the exact binary value rounded half away from zero
//!   (core rounds exact ties to even: `{:.0}` of 2.5 is "2" there, "3" here),
//!   never prints "-0.000", prints NaN as 0 and clamps magnitudes to
//!   [`FIXED_LIMIT`], far beyond any position, feed or setting.

use core::fmt::{self, Write};

pub mod trig;

/// Exact `f32` powers of ten: 10^10 = 2^10 * 5^10 and 5^10 < 2^24.
const POW10_F32: [f32; 11] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10];

/// Significant digits kept; the rest only move the exponent. 19 digits are
/// 63 bits, far more than f32's 24, so dropping the tail cannot matter
/// except within 10^-18 of a rounding midpoint.
const MAX_SIG: u32 = 19;

/// A decimal number being read: `mant * 10^exp`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Decimal {
    pub mant: u64,
    pub exp: i32,
    /// Significant digits in `mant` (leading zeros do not count).
    sig: u32,
    /// Every digit seen, zeros included: zero digits means no number.
    pub digits: u32,
}

impl Decimal {
    /// Appends one digit (0-9); `frac` says whether it follows the point.
    #[inline]
    pub fn push(&mut self, d: u8, frac: bool) {
        self.digits += 1;
        if self.sig < MAX_SIG {
            if self.sig > 0 || d != 0 {
                self.mant = self.mant * 10 + u64::from(d);
                self.sig += 1;
            }
            self.exp -= i32::from(frac);
        } else if !frac {
            self.exp += 1;
        }
    }

    /// The nearest `f32` (see the module notes for the 1-ulp exception).
    /// Too large for `f32` gives infinity, for the caller to refuse.
    pub fn to_f32(self) -> f32 {
        let Decimal { mant, exp, sig, .. } = self;
        if mant == 0 {
            return 0.0;
        }
        if mant < 1 << 24 && (-10..=10).contains(&exp) {
            // Both operands exact: one correctly rounded operation.
            let p = POW10_F32
                .get(exp.unsigned_abs() as usize)
                .copied()
                .unwrap_or(1.0);
            return if exp < 0 {
                mant as f32 / p
            } else {
                mant as f32 * p
            };
        }
        // The value lies in [10^(top-1), 10^top).
        let top = exp + sig as i32;
        if top > 39 {
            return f32::INFINITY;
        }
        if top < -46 {
            // Below 10^-46, less than half the smallest subnormal.
            return 0.0;
        }
        wide_to_f32(mant, exp)
    }
}

/// `mant · 10^exp` rounded to `f32` with integer arithmetic only: the
/// board has no double-precision unit, and soft `f64` division was the
/// only reason this path needed one. The value is carried as a 128-bit
/// integer times a power of two, scaled by at most 10^19 at a time (a `u64`
/// factor), with every bit shifted or divided away kept as a sticky bit in
/// bit 0, which lies 39 bits or more below the rounding point (the integer
/// keeps 64 bits or more): the conversion to `f32` then rounds as if it
/// saw the exact value. Only scaling up (more than 19 digits before the
/// point) rounds before multiplying, an error of 2^-63 (relative); and a
/// subnormal result (below 1.2e-38) is rounded twice.
fn wide_to_f32(mant: u64, exp: i32) -> f32 {
    let mut m = u128::from(mant);
    let mut e2: i32 = 0;
    let mut sticky = false;
    let mut e = exp;
    while e != 0 {
        let k = e.unsigned_abs().min(19);
        let p = 10u64.pow(k);
        if e > 0 {
            // At most 64 bits before the multiply: the product fits.
            let excess = 64u32.saturating_sub(m.leading_zeros());
            sticky |= m & ((1u128 << excess) - 1) != 0;
            m >>= excess;
            e2 += excess as i32;
            m *= u128::from(p);
            e -= k as i32;
        } else {
            // Top bit at 127: the quotient keeps 64 bits or more.
            let lz = m.leading_zeros();
            m <<= lz;
            e2 -= lz as i32;
            let q = m / u128::from(p);
            sticky |= q * u128::from(p) != m;
            m = q;
            e += k as i32;
        }
    }
    libm::scalbnf((m | u128::from(sticky)) as f32, e2)
}

/// A plain decimal, `[+-]digits[.digits]` with at least one digit: GRBL's
/// `$n=value` syntax. No blanks, exponents, `inf` or `nan`; `None` for
/// those and for values too large for `f32`.
pub fn parse_f32(text: &[u8]) -> Option<f32> {
    let (neg, body) = match text.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, text),
    };
    let mut d = Decimal::default();
    let mut frac = false;
    for &b in body {
        match b {
            b'0'..=b'9' => d.push(b - b'0', frac),
            b'.' if !frac => frac = true,
            _ => return None,
        }
    }
    if d.digits == 0 {
        return None;
    }
    let v = d.to_f32();
    if !v.is_finite() {
        return None;
    }
    Some(if neg { -v } else { v })
}

/// Largest magnitude [`write_fixed`] prints (about 2^40); larger values and
/// infinities print as this, with their sign.
pub const FIXED_LIMIT: f32 = 1e12;

/// `v` limited to `lo..=hi` (`lo` for NaN). Not `f32::clamp`: its
/// `lo <= hi` assertion formats floats in its panic message, which links
/// core's float printing (about 20 KB) into the image; `cargo xtask build`
/// refuses an image that has it.
#[inline]
pub fn clamp(v: f32, lo: f32, hi: f32) -> f32 {
    v.max(lo).min(hi)
}

/// `x` rounded half away from zero, as `libm::roundf` rounds, if within
/// ±1e9 (`None` beyond, or not a number). One conversion each way and a
/// compare: `roundf` took about twenty instructions, and the planner
/// rounds every axis of every move (bench-target's `plan_block_insns`).
/// Exact: below 2^24 the integer part converts back exactly and `x` less
/// it is exactly the fraction; above, `x` is a whole number.
// NaN fails the one comparison too (two tests cost 18 instructions of
// `plan_block_insns`).
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn round_i32(x: f32) -> Option<i32> {
    if !(libm::fabsf(x) <= 1.0e9) {
        return None;
    }
    let t = x as i32;
    let frac = x - t as f32;
    Some(if frac >= 0.5 {
        t + 1
    } else if frac <= -0.5 {
        t - 1
    } else {
        t
    })
}

/// Square root, correctly rounded: the FPU's `VSQRT.F32` on the board,
/// libm's elsewhere (both IEEE 754, so host-sim computes the same bits).
/// core has no float square root on stable Rust, and libm's for this
/// target is its software one: every square root of the planner's passes
/// cost a hundred instructions or so, a third of `plan_block_insns` and
/// two fifths of `plan_chord_scurve_insns` (`cargo xtask bench-target`:
/// 11,052 -> 7,532 and 153,835 -> 96,317). A call, not inlined: inlined
/// at its forty-odd call sites it took 2 % fewer instructions but 3.4 KB
/// more flash (99.9 % of the budget). The asm names no FPU register
/// class (that needs the `vfp2` target feature, which the
/// `thumbv7em-none-eabihf` spec leaves out of Rust's view although the
/// FPU is there): it moves `x` through a core register into `s0`, saved
/// and restored around it. clippy refuses `libm::sqrtf` elsewhere
/// (`clippy.toml`).
#[inline(never)]
#[allow(unsafe_code)]
pub fn sqrt(x: f32) -> f32 {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    {
        let r: u32;
        // SAFETY: register level only: VSQRT.F32 on `s0`, which is
        // pushed before and popped after, between two core registers; no
        // memory but those two stack words, no flags.
        unsafe {
            core::arch::asm!(
                "vpush {{s0}}",
                "vmov s0, {x}",
                "vsqrt.f32 s0, s0",
                "vmov {r}, s0",
                "vpop {{s0}}",
                x = in(reg) x.to_bits(),
                r = lateout(reg) r,
                options(pure, nomem, preserves_flags),
            );
        }
        f32::from_bits(r)
    }
    #[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
    {
        #[allow(clippy::disallowed_methods)]
        libm::sqrtf(x)
    }
}

/// Cube root of `x` ≥ 0 (0 for anything else), in `f32` only: libm's
/// `cbrtf` finishes in `f64`, soft-float on this FPU (the image check
/// refuses it). A first guess from the exponent bits, then Newton steps
/// `y ← y − (y³ − x)/(3y²)`, each about doubling the correct bits.
pub fn cbrt(x: f32) -> f32 {
    if x.is_nan() || x <= 0.0 {
        return 0.0;
    }
    if x.is_infinite() {
        return x;
    }
    let mut y = f32::from_bits(x.to_bits() / 3 + 0x2a51_37a0);
    for _ in 0..4 {
        y -= (y * y * y - x) / (3.0 * y * y);
    }
    y
}

/// Most decimals [`write_fixed`] prints; more are clamped to this.
pub const MAX_DECIMALS: u8 = 6;

/// `|v| * 10^decimals` rounded half away from zero, exactly (integer
/// arithmetic on the float's bits), and the sign. NaN is 0.
fn scaled(v: f32, decimals: u8) -> (bool, u64) {
    let v = if v.is_nan() {
        0.0
    } else {
        clamp(v, -FIXED_LIMIT, FIXED_LIMIT)
    };
    let bits = v.to_bits();
    let neg = bits >> 31 != 0;
    let biased = ((bits >> 23) & 0xff) as i32;
    let frac = u64::from(bits & 0x7f_ffff);
    let (m, e2) = if biased == 0 {
        (frac, -149)
    } else {
        (frac | 1 << 23, biased - 150)
    };
    // m < 2^24 and 10^6 < 2^20: the product fits in 44 bits, and with
    // |v| <= 2^40 the left shift below is at most 17.
    let s = m * 10u64.pow(u32::from(decimals.min(MAX_DECIMALS)));
    let n = if e2 >= 0 {
        s << e2
    } else if e2 <= -64 {
        0
    } else {
        let sh = e2.unsigned_abs();
        let half = 1u64 << (sh - 1);
        let rest = s & ((1u64 << sh) - 1);
        (s >> sh) + u64::from(rest >= half)
    };
    (neg && n != 0, n)
}

/// Writes `v` with exactly `decimals` digits after the point (none and no
/// point for 0), like `{:.N}` but rounding ties away from zero, never
/// writing "-0.000", NaN as 0, magnitudes clamped to [`FIXED_LIMIT`].
pub fn write_fixed(w: &mut (impl Write + ?Sized), v: f32, decimals: u8) -> fmt::Result {
    let d = decimals.min(MAX_DECIMALS);
    let (neg, n) = scaled(v, d);
    write_scaled(w, neg, n, d, false)
}

/// Writes `v` with at most `max_decimals` decimals and no trailing zeros
/// (`10`, `12.5`, `0.125`): the short form for `$G`'s F and S. Same
/// rounding and limits as [`write_fixed`].
pub fn write_short(w: &mut (impl Write + ?Sized), v: f32, max_decimals: u8) -> fmt::Result {
    let d = max_decimals.min(MAX_DECIMALS);
    let (neg, n) = scaled(v, d);
    write_scaled(w, neg, n, d, true)
}

fn write_scaled(
    w: &mut (impl Write + ?Sized),
    neg: bool,
    n: u64,
    d: u8,
    trim: bool,
) -> fmt::Result {
    let p = 10u64.pow(u32::from(d));
    if neg {
        w.write_char('-')?;
    }
    write!(w, "{}", n / p)?;
    let mut f = n % p;
    let mut d = u32::from(d);
    if trim {
        while d > 0 && f.is_multiple_of(10) {
            f /= 10;
            d -= 1;
        }
    }
    if d == 0 {
        return Ok(());
    }
    // Fractional digits, most significant first, zero-padded.
    let mut buf = [b'0'; MAX_DECIMALS as usize];
    for slot in buf.iter_mut().take(d as usize).rev() {
        *slot = b'0' + (f % 10) as u8;
        f /= 10;
    }
    w.write_char('.')?;
    for &b in buf.iter().take(d as usize) {
        w.write_char(char::from(b))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn round_i32_rounds_as_roundf() {
        let edge = [
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            0.499_999_97,
            -0.499_999_97,
            0.500_000_06,
            8_388_607.5,
            -8_388_607.5,
            8_388_609.0,
            16_777_217.0,
            1.0e9,
            -1.0e9,
            123.456,
            -0.000_001,
        ];
        let mut x = 0x1234_5678u32;
        let randoms = (0..20_000).map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x as f32 / u32::MAX as f32 - 0.5) * 2.0e4
        });
        for v in edge.into_iter().chain(randoms) {
            assert_eq!(round_i32(v), Some(libm::roundf(v) as i32), "{v}");
        }
        for v in [f32::NAN, f32::INFINITY, -f32::INFINITY, 1.1e9, -2.0e9] {
            assert_eq!(round_i32(v), None, "{v}");
        }
    }

    use super::*;
    use std::string::String;

    fn fixed(v: f32, d: u8) -> String {
        let mut s = String::new();
        write_fixed(&mut s, v, d).unwrap();
        s
    }

    fn short(v: f32, d: u8) -> String {
        let mut s = String::new();
        write_short(&mut s, v, d).unwrap();
        s
    }

    #[test]
    fn cube_roots_in_f32() {
        for x in [
            1e-9f32, 1e-4, 0.09, 0.45, 1.0, 8.0, 27.0, 450.0, 5000.0, 1e9, 3.0e30,
        ] {
            let want = (x as f64).cbrt();
            let got = f64::from(cbrt(x));
            assert!(
                (got - want).abs() <= 2e-7 * want,
                "{x}: {got} against {want}"
            );
        }
        assert_eq!(cbrt(0.0), 0.0);
        assert_eq!(cbrt(-8.0), 0.0);
        assert_eq!(cbrt(f32::NAN), 0.0);
        assert_eq!(cbrt(f32::INFINITY), f32::INFINITY);
    }

    #[test]
    fn parses_plain_decimals() {
        assert_eq!(parse_f32(b"1.5"), Some(1.5));
        assert_eq!(parse_f32(b"-0.001"), Some(-0.001));
        assert_eq!(parse_f32(b"+12"), Some(12.0));
        assert_eq!(parse_f32(b".5"), Some(0.5));
        assert_eq!(parse_f32(b"5."), Some(5.0));
        assert_eq!(parse_f32(b"000000000000000000000000123.25"), Some(123.25));
        assert_eq!(parse_f32(b"0.1000000000000000000000001"), Some(0.1));
        assert_eq!(parse_f32(b"16777217"), Some(16_777_216.0));
        assert_eq!(
            parse_f32(b"340282350000000000000000000000000000000"),
            Some(f32::MAX)
        );
    }

    #[test]
    fn refuses_what_is_not_a_plain_decimal() {
        for t in [
            &b""[..],
            b"-",
            b".",
            b"1.2.3",
            b"1e5",
            b"inf",
            b"nan",
            b" 1",
            b"1 ",
            b"--1",
            b"0x10",
        ] {
            assert_eq!(parse_f32(t), None, "{:?}", core::str::from_utf8(t));
        }
        // 10^39 overflows f32.
        let mut big = String::from("1");
        big.push_str(&"0".repeat(39));
        assert_eq!(parse_f32(big.as_bytes()), None);
    }

    #[test]
    fn tiny_values_round_to_zero_or_subnormals() {
        let mut t = String::from("0.");
        t.push_str(&"0".repeat(60));
        t.push('1');
        assert_eq!(parse_f32(t.as_bytes()), Some(0.0));
        let sub = "0.000000000000000000000000000000000000000000001401298464324817";
        assert_eq!(parse_f32(sub.as_bytes()), Some(f32::from_bits(1)));
    }

    #[test]
    fn fixed_matches_the_usual_text() {
        assert_eq!(fixed(0.0, 3), "0.000");
        assert_eq!(fixed(1.0, 3), "1.000");
        assert_eq!(fixed(-12.3456, 3), "-12.346");
        assert_eq!(fixed(0.1, 4), "0.1000");
        assert_eq!(fixed(1234.5678, 0), "1235");
        assert_eq!(fixed(99.9996, 3), "100.000");
    }

    #[test]
    fn fixed_never_writes_negative_zero() {
        assert_eq!(fixed(-0.0, 3), "0.000");
        assert_eq!(fixed(-0.0004, 3), "0.000");
        assert_eq!(fixed(-0.4, 0), "0");
    }

    #[test]
    fn fixed_rounds_ties_away_from_zero() {
        assert_eq!(fixed(2.5, 0), "3");
        assert_eq!(fixed(-2.5, 0), "-3");
        assert_eq!(fixed(0.125, 2), "0.13");
    }

    #[test]
    fn fixed_clamps_nan_and_huge() {
        assert_eq!(fixed(f32::NAN, 1), "0.0");
        assert_eq!(fixed(f32::INFINITY, 0), "999999995904");
        assert_eq!(fixed(-1e30, 0), "-999999995904");
        assert_eq!(fixed(1.0, 200), "1.000000");
    }

    #[test]
    fn short_trims_zeros() {
        assert_eq!(short(0.0, 3), "0");
        assert_eq!(short(10.0, 3), "10");
        assert_eq!(short(12.5, 3), "12.5");
        assert_eq!(short(-0.125, 3), "-0.125");
        assert_eq!(short(3.937_008, 3), "3.937");
    }
}
