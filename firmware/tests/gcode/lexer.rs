//! The lexer on its own: numbers, words, comments, checksums, parameters.

use burin::gcode::{ErrorKind, Lexer, Params, Token, Word};
use proptest::prelude::*;

fn words(line: &str) -> Result<Vec<Word>, ErrorKind> {
    let mut p = Params::new();
    let mut lx = Lexer::new(line.as_bytes()).map_err(|e| e.kind)?;
    let mut v = Vec::new();
    while let Some(t) = lx.next_token(&mut p).map_err(|e| e.kind)? {
        if let Token::Word(w) = t {
            v.push(w);
        }
    }
    Ok(v)
}

#[test]
fn words_and_columns() {
    let w = words("G1X0Y8 x+1.5 (c) Z.5 a-0.").unwrap();
    let got: Vec<(char, f32, u16)> = w
        .iter()
        .map(|w| (w.letter as char, w.value, w.col))
        .collect();
    assert_eq!(
        got,
        vec![
            ('G', 1.0, 1),
            ('X', 0.0, 3),
            ('Y', 8.0, 5),
            ('X', 1.5, 8),
            ('Z', 0.5, 18),
            ('A', -0.0, 22)
        ]
    );
}

#[test]
fn blanks_inside_numbers_and_words() {
    let w = words("G 0 1 X 1 0 . 5").unwrap();
    assert_eq!(w.len(), 2);
    assert_eq!(w[0].tenths(), Some(10));
    assert_eq!(w[1].value, 10.5);
}

#[test]
fn message_and_delimiters() {
    let mut p = Params::new();
    let mut lx = Lexer::new(b"G1 (MSG, Hello ) X1").unwrap();
    assert!(matches!(lx.next_token(&mut p), Ok(Some(Token::Word(_)))));
    assert!(matches!(
        lx.next_token(&mut p),
        Ok(Some(Token::Message {
            text: b"Hello",
            col: 4
        }))
    ));
    let lx = Lexer::new(b"  /G1 X1").unwrap();
    assert!(lx.block_delete);
    let lx = Lexer::new(b"%").unwrap();
    assert!(lx.percent);
}

#[test]
fn checksum() {
    // XOR of "N1 G1 X5" is 0x4d ^ ... computed here, not hard-coded.
    let body = "N1 G1 X5";
    let x = body.bytes().fold(0u8, |a, b| a ^ b);
    assert!(words(&format!("{body}*{x}")).is_ok());
    assert!(matches!(
        words(&format!("{body}*{}", x ^ 1)),
        Err(ErrorKind::ChecksumMismatch { .. })
    ));
    // Inside brackets `*` multiplies.
    assert_eq!(words("X[2*3]").unwrap()[0].value, 6.0);
}

#[test]
fn immediate_assignment() {
    let w = words("G1 #3=2 Y#3 #<x y>=[#3*2] Z#<XY>").unwrap();
    assert_eq!(
        w.iter().map(|w| w.value).collect::<Vec<_>>(),
        vec![1.0, 2.0, 4.0]
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 5_000, ..ProptestConfig::default() })]

    /// Our fast decimal path rounds exactly like core's correctly rounded parser.
    #[test]
    fn numbers_round_like_core(int in 0u32..10_000_000, frac in 0u32..1_000_000, digits in 0usize..7, neg in any::<bool>()) {
        let frac_s = format!("{frac:06}");
        let s = format!("{}{int}.{}", if neg { "-" } else { "" }, &frac_s[..digits]);
        let w = words(&format!("X{s}")).unwrap();
        prop_assert_eq!(w[0].value, s.parse::<f32>().unwrap(), "{}", s);
    }
}
