//! `burin::num` against std's correctly rounded parser and exact formatter.
//!
//! Parsing: numbers of up to 19 significant digits must equal
//! `str::parse::<f32>` bit for bit (one exact f32 operation up to 7 digits
//! and 10 decimals, 128-bit integer scaling beyond), unless the result is
//! subnormal. Longer ones may differ by at most 1 ulp: digits past the
//! 19th are dropped, so only a decimal within 10^-18 (relative) of the
//! midpoint of two floats can round to the other neighbour.
//!
//! Formatting: `write_fixed(v, n)` must equal `format!("{v:.n}")` except for
//! the two documented differences: exact ties round away from zero (std:
//! to even), and values that round to zero print without a minus sign.

use burin::gcode::{Lexer, Params, Token};
use burin::num::{parse_f32, write_fixed};
use proptest::prelude::*;

fn ulps(a: f32, b: f32) -> u32 {
    assert_eq!(a.is_sign_negative(), b.is_sign_negative(), "{a} vs {b}");
    a.to_bits().abs_diff(b.to_bits())
}

/// Significant digits of a plain decimal (leading zeros do not count).
fn significant(s: &str) -> usize {
    let digits: String = s.chars().filter(char::is_ascii_digit).collect();
    let t = digits.trim_start_matches('0');
    t.len()
}

fn frac_digits(s: &str) -> usize {
    s.split_once('.').map_or(0, |(_, f)| f.len())
}

fn check_parse(s: &str, got: f32) {
    let want: f32 = s.parse().unwrap();
    let d = ulps(got, want);
    let exact = significant(s) <= 7 && frac_digits(s) <= 10
        || significant(s) <= 19 && (want == 0.0 || want.is_normal());
    if exact {
        assert_eq!(d, 0, "{s}: got {got:e}, std {want:e}");
    } else {
        assert!(d <= 1, "{s}: got {got:e}, std {want:e}, {d} ulps");
    }
}

fn lex_value(line: &str) -> f32 {
    let mut p = Params::new();
    let mut lx = Lexer::new(line.as_bytes()).unwrap();
    match lx.next_token(&mut p) {
        Ok(Some(Token::Word(w))) => w.value,
        other => panic!("{line}: {other:?}"),
    }
}

/// `a` and `b` differ only as documented (tie or negative zero).
fn fixed_ok(v: f32, n: u8, ours: &str, std: &str) -> bool {
    if ours == std {
        return true;
    }
    let zero = std
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.');
    if zero && std.starts_with('-') && ours == &std[1..] {
        return true;
    }
    // An exact tie: |v| * 10^n has a fractional part of exactly one half
    // (exact in f64: 24 + 3n bits).
    let x = f64::from(v.abs()) * 10f64.powi(i32::from(n));
    x - x.floor() == 0.5
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(20_000))]

    #[test]
    fn short_numbers_parse_exactly(
        s in "[0-9]{1,7}|[0-9]{0,4}\\.[0-9]{1,3}|[0-9]{1,3}\\.[0-9]{0,4}|0?\\.0{0,5}[0-9]{1,5}"
    ) {
        prop_assert!(significant(&s) <= 7 && frac_digits(&s) <= 10);
        check_parse(&s, parse_f32(s.as_bytes()).unwrap());
    }

    #[test]
    fn long_numbers_parse_within_one_ulp(s in "[0-9]{1,30}(\\.[0-9]{0,40})?") {
        prop_assume!(s.len() < 200);
        match parse_f32(s.as_bytes()) {
            Some(v) => check_parse(&s, v),
            None => prop_assert!(s.parse::<f32>().unwrap().is_infinite(), "{}", s),
        }
    }

    #[test]
    fn small_fractions_parse_within_one_ulp(z in 0usize..50, s in "[1-9][0-9]{0,12}") {
        let t = format!("0.{}{}", "0".repeat(z), s);
        check_parse(&t, parse_f32(t.as_bytes()).unwrap());
    }

    #[test]
    fn lexer_numbers_agree(s in "[0-9]{1,12}\\.[0-9]{1,12}") {
        let line = format!("X{s}");
        check_parse(&s, lex_value(&line));
        // Blanks inside a number are ignored (LinuxCNC).
        let spaced: String = s.chars().flat_map(|c| [c, ' ']).collect();
        check_parse(&s, lex_value(&format!("X{spaced}")));
    }

    /// The lexer's fast path for plain numbers (`X1.5`, `X-1.5`, blanks
    /// after) must give exactly, bit for bit, what the general path gives
    /// (a blank after the letter, brackets, a unary minus in brackets).
    #[test]
    fn fast_and_general_number_paths_agree(
        s in "[0-9]{1,6}|[0-9]{0,5}\\.[0-9]{1,6}|[0-9]{1,5}\\.",
        tail in prop::sample::select(vec!["", " ", "\t Y1", " (c)", ";x"]),
    ) {
        let fast = lex_value(&format!("X{s}{tail}"));
        let general = lex_value(&format!("X {s}{tail}"));
        prop_assert_eq!(fast.to_bits(), general.to_bits(), "{}", s);
        prop_assert_eq!(fast.to_bits(), lex_value(&format!("X[{s}]{tail}")).to_bits(), "{}", s);
        let neg = lex_value(&format!("X-{s}{tail}"));
        prop_assert_eq!(neg.to_bits(), (-fast).to_bits(), "{}", s);
        prop_assert_eq!(neg.to_bits(), lex_value(&format!("X [-{s}]{tail}")).to_bits(), "{}", s);
    }

    #[test]
    fn fixed_matches_std(v in -1.0e7f32..1.0e7, n in 0u8..=4) {
        let mut ours = String::new();
        write_fixed(&mut ours, v, n).unwrap();
        let std = format!("{v:.*}", usize::from(n));
        prop_assert!(fixed_ok(v, n, &ours, &std), "{v:e} .{n}: ours {ours}, std {std}");
    }

    #[test]
    fn fixed_matches_std_on_short_decimals(i in -10_000_000i32..10_000_000, n in 0u8..=4) {
        // Values that are themselves short decimals, as positions are.
        let v = i as f32 / 1000.0;
        let mut ours = String::new();
        write_fixed(&mut ours, v, n).unwrap();
        let std = format!("{v:.*}", usize::from(n));
        prop_assert!(fixed_ok(v, n, &ours, &std), "{v:e} .{n}: ours {ours}, std {std}");
    }

    #[test]
    fn fixed_then_parse_round_trips(i in -100_000_000i32..100_000_000) {
        // Three decimals printed and read back give the same millimetres.
        let v = i as f32 / 1000.0;
        let mut s = String::new();
        write_fixed(&mut s, v, 3).unwrap();
        let back = parse_f32(s.as_bytes()).unwrap();
        check_parse(&s, back);
        prop_assert!((back - v).abs() <= v.abs() * 1e-6 + 5e-4, "{} -> {} -> {}", v, s, back);
    }
}

#[test]
fn ties_and_negative_zero_are_the_documented_differences() {
    let mut s = String::new();
    write_fixed(&mut s, 0.0625, 3).unwrap();
    assert_eq!(s, "0.063");
    assert_eq!(format!("{:.3}", 0.0625f32), "0.062");
    assert!(fixed_ok(0.0625, 3, "0.063", "0.062"));
    assert!(fixed_ok(-0.0001, 3, "0.000", "-0.000"));
    assert!(!fixed_ok(1.0, 3, "1.001", "1.000"));
}
