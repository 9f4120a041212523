//! How a text file writes its numbers, so that a file moved as it is ([`super::transform_file`])
//! writes its moved coordinates the way it wrote them: as many decimals as its most precise
//! value (shifted by a change of unit), or in exponent notation with as many significant digits
//! when it used it.

use std::ops::Range;

/// The style learned from a file's tokens of one kind (coordinates, or normals).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct NumberStyle {
    /// The most digits after the decimal point (of the mantissa, in exponent notation).
    decimals: u32,
    /// True when any token is written with an exponent (`1.5e-3`).
    exponent: bool,
}

/// The styles of a file's positions and of its normals, learned over a first pass
/// ([`NumberStyle::learn`]), then made ready for writing ([`Styles::for_writing`]).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Styles {
    pub(super) position: NumberStyle,
    pub(super) normal: NumberStyle,
}

impl Styles {
    /// As the moved values are written: positions shifted by the motion's `scale` (a change of
    /// unit), normals with at least six decimals.
    pub(super) fn for_writing(self, scale: f64) -> Self {
        Self { position: self.position.scaled(scale), normal: self.normal.at_least(6) }
    }
}

/// The most decimals written: beyond 17 an `f64` has no more digits to give.
const MAX_DECIMALS: i64 = 17;

impl NumberStyle {
    /// Learns from one token (a number as the file wrote it).
    pub(super) fn learn(&mut self, token: &str) {
        let mantissa = match token.find(['e', 'E']) {
            Some(i) => {
                self.exponent = true;
                &token[..i]
            }
            None => token,
        };
        if let Some((_, frac)) = mantissa.split_once('.') {
            self.decimals = self.decimals.max(frac.len().min(MAX_DECIMALS as usize) as u32);
        }
    }

    /// The style of values multiplied by `scale` (a change of unit, e.g. 1000 from metres to
    /// millimetres): as many fewer decimals as the scale has powers of ten, rounded towards more
    /// (exponent notation keeps its significant digits).
    pub(super) fn scaled(self, scale: f64) -> Self {
        if self.exponent {
            return self; // as many significant digits as before
        }
        let shift = (-scale.log10() - 1e-9).ceil() as i64;
        Self { decimals: (self.decimals as i64 + shift).clamp(0, MAX_DECIMALS) as u32, ..self }
    }

    /// This style with at least `decimals` decimals (unit normals written as integers would lose
    /// their direction once turned).
    pub(super) fn at_least(self, decimals: u32) -> Self {
        Self { decimals: self.decimals.max(decimals), ..self }
    }

    /// Appends `v` in this style: with its decimals, in exponent form (`1.018757e2`) when the
    /// file used exponents. A value that rounds to zero is written without a sign.
    pub(super) fn write(self, v: f64, out: &mut Vec<u8>) {
        let d = self.decimals as usize;
        if !self.exponent && write_fixed(v, d, out) {
            return;
        }
        let mut s = if self.exponent { format!("{v:.d$e}") } else { format!("{v:.d$}") };
        if s.starts_with('-') && s[1..].bytes().all(|b| matches!(b, b'0' | b'.')) {
            s.remove(0);
        }
        out.extend_from_slice(s.as_bytes());
    }
}

/// Appends `line` with the byte ranges `edits` replaced by their values in `style`, every other
/// byte as it was. `edits` (a few per line) do not overlap; they are put in order here (an
/// insertion sort: the library's sorts would add kilobytes to the WebAssembly module for this).
fn splice(line: &[u8], edits: &mut [(Range<usize>, f64, NumberStyle)], out: &mut Vec<u8>) {
    for i in 1..edits.len() {
        let mut j = i;
        while j > 0 && edits[j - 1].0.start > edits[j].0.start {
            edits.swap(j - 1, j);
            j -= 1;
        }
    }
    let mut at = 0;
    for (range, v, style) in edits {
        out.extend_from_slice(&line[at..range.start]);
        style.write(*v, out);
        at = range.end;
    }
    out.extend_from_slice(&line[at..]);
}

/// Appends `v` with `d` decimals without going through `core::fmt` (ten times faster on the
/// millions of values of a large text file): `v` times `10^d` rounded to an integer, written with
/// the decimal point put back. False (nothing written) when that integer is beyond 2^53, where
/// the caller formats it the general way.
fn write_fixed(v: f64, d: usize, out: &mut Vec<u8>) -> bool {
    const POW10: [f64; 18] =
        [1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17];
    let scaled = (v * POW10[d.min(17)]).round();
    if scaled.is_nan() || scaled.abs() >= 9.007_199_254_740_992e15 {
        return false;
    }
    let mut n = scaled.abs() as u64;
    let mut digits = [0u8; 24];
    let mut len = 0;
    while n > 0 || len <= d {
        digits[len] = b'0' + (n % 10) as u8;
        n /= 10;
        len += 1;
    }
    if scaled < 0.0 {
        out.push(b'-');
    }
    for k in (0..len).rev() {
        out.push(digits[k]);
        if k == d && d > 0 {
            out.push(b'.');
        }
    }
    true
}

/// A text file copied with some of its lines rewritten ([`Rewrite::line`]), every byte between
/// them (other lines, line endings) as it was.
pub(super) struct Rewrite<'a> {
    bytes: &'a [u8],
    out: Vec<u8>,
    /// How far `bytes` is copied or rewritten.
    copied: usize,
}

impl<'a> Rewrite<'a> {
    pub(super) fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, out: Vec::with_capacity(bytes.len() + bytes.len() / 8), copied: 0 }
    }

    /// `line` (a sub-slice of the file, after the lines rewritten before) with `edits` spliced in.
    pub(super) fn line(&mut self, line: &str, edits: &mut [(Range<usize>, f64, NumberStyle)]) {
        let start = line.as_ptr() as usize - self.bytes.as_ptr() as usize;
        self.out.extend_from_slice(&self.bytes[self.copied..start]);
        splice(line.as_bytes(), edits, &mut self.out);
        self.copied = start + line.len();
    }

    /// `token` (a sub-slice of the file, after what was rewritten before) replaced by `v` in
    /// `style`: for records that may span lines (OFF).
    pub(super) fn token(&mut self, token: &str, v: f64, style: NumberStyle) {
        let start = token.as_ptr() as usize - self.bytes.as_ptr() as usize;
        self.out.extend_from_slice(&self.bytes[self.copied..start]);
        style.write(v, &mut self.out);
        self.copied = start + token.len();
    }

    /// The file: its rewritten lines and everything else.
    pub(super) fn finish(mut self) -> Vec<u8> {
        self.out.extend_from_slice(&self.bytes[self.copied..]);
        self.out
    }
}

/// The byte range of `token` within `line` (`token` a sub-slice of `line`).
pub(super) fn span(line: &str, token: &str) -> Range<usize> {
    let start = token.as_ptr() as usize - line.as_ptr() as usize;
    start..start + token.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn written(style: NumberStyle, v: f64) -> String {
        let mut out = Vec::new();
        style.write(v, &mut out);
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn learns_the_most_decimals_and_exponents() {
        let mut s = NumberStyle::default();
        for t in ["1", "-2.5", "3.125", "4.0"] {
            s.learn(t);
        }
        assert_eq!(written(s, 1.0 / 3.0), "0.333");
        assert_eq!(written(s, -0.0001), "0.000");
        assert_eq!(written(s.scaled(1000.0), 1234.5678), "1235");
        assert_eq!(written(s.scaled(0.0254), 1.0), "1.00000");
        assert_eq!(written(s.scaled(1.0), 2.0), "2.000");
        assert_eq!(written(NumberStyle::default().at_least(6), 0.5), "0.500000");
        s.learn("1.5e-3");
        assert_eq!(written(s, 0.1 + 0.2), "3.000e-1");
        assert_eq!(written(s.scaled(1000.0), -1234.5678), "-1.235e3");
        assert_eq!(written(s, -1e-9), "-1.000e-9");
    }

    #[test]
    fn fixed_decimals_round_to_the_nearest_step() {
        let mut state = 11u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for k in 0..20_000 {
            let d = k % 10;
            let v = (next() - 0.5) * 10f64.powi((k % 13) as i32 - 3);
            let mut out = Vec::new();
            if !write_fixed(v, d, &mut out) {
                assert!(v.abs() * 10f64.powi(d as i32) >= 9e15 && out.is_empty(), "{v} {d}");
                continue;
            }
            let text = String::from_utf8(out).unwrap();
            assert_eq!(text.split_once('.').map_or(0, |(_, f)| f.len()), d, "{text}");
            let back: f64 = text.parse().unwrap();
            assert!(
                (back - v).abs() <= 0.5 * 10f64.powi(-(d as i32)) * (1.0 + 1e-9) + v.abs() * 1e-15,
                "{v} {d}: {text}"
            );
        }
        let mut out = Vec::new();
        assert!(!write_fixed(1e20, 3, &mut out) && out.is_empty(), "beyond 2^53: the general way");
        assert_eq!(written(NumberStyle { decimals: 3, exponent: false }, 1e20), "100000000000000000000.000");
    }

    #[test]
    fn splices_values_into_a_line() {
        let line = "v 1.0 2.0 3.0 # c";
        let toks: Vec<&str> = line.split(' ').collect();
        let mut s = NumberStyle::default();
        s.learn("1.0");
        let mut edits: Vec<_> =
            toks[1..4].iter().zip([5.0, 6.75, -7.0]).map(|(t, v)| (span(line, t), v, s)).rev().collect();
        let mut out = Vec::new();
        splice(line.as_bytes(), &mut edits, &mut out);
        assert_eq!(String::from_utf8(out).unwrap(), "v 5.0 6.8 -7.0 # c");
    }
}
