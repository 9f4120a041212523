//! How a text file writes its numbers, so that a file moved as it is ([`super::transform_file`])
//! writes its moved coordinates the way it wrote them: as many decimals as its most precise
//! value (shifted by a change of unit); in exponent notation with as many digits when it used
//! it, its exponents written as it wrote them (`e-05`, `E+002`); and, where it used both (what
//! C's `%g` and C++ streams write: `0.11349`, `9.9999997e-05`), the same way, with as many
//! significant digits.

use super::motion::{Bounds, Motion};
use std::ops::Range;

/// The style learned from a file's tokens of one kind (coordinates, or normals).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct NumberStyle {
    /// The most digits after the decimal point (of the mantissa, in exponent notation).
    decimals: u32,
    /// True when any token is written with an exponent (`1.5e-3`).
    exponent: bool,
    /// True when any token is written without one.
    plain: bool,
    /// The most significant digits of a token.
    significant: u32,
    /// The most digits of an exponent (`e-05`: 2), whether a positive one has its `+`, and
    /// whether it is written `E` (a positive one gets its `+` too when exponents are padded to
    /// two digits, as C writes them).
    exponent_digits: u32,
    exponent_plus: bool,
    exponent_upper: bool,
    /// The decimals of the first token, and whether another had other decimals: a file that
    /// does not pad its numbers to one number of decimals (`%g`, the shortest form) gets its
    /// trailing zeros left out.
    first_decimals: Option<u32>,
    varied: bool,
}

/// The styles of a file's positions and of its normals, learned over a first pass
/// ([`NumberStyle::learn`]), then made ready for writing ([`Styles::for_writing`]).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Styles {
    pub(super) position: NumberStyle,
    pub(super) normal: NumberStyle,
    /// The positions' bounds, from [`Styles::bound`].
    bounds: Bounds,
}

/// The coarsest step a moved position is written with, as a fraction of the cloud's diagonal:
/// a file written with few decimals (a CAD cube's `1.0 0.0 1.0`) gets more once turned, since
/// its values no longer fall on its grid, and rounding them back onto it would distort the shape
/// (by up to 0.05 of a 2-unit cube's side at one decimal). A scan in millimetre steps over a few
/// metres keeps its three decimals.
const STEP_OF_DIAGONAL: f64 = 1e-3;

impl Styles {
    /// Takes in one position (finite values only), whose bounds set the coarsest step the moved
    /// positions are written with ([`STEP_OF_DIAGONAL`]).
    pub(super) fn bound(&mut self, p: [f64; 3]) {
        self.bounds.add(p);
    }

    /// The positions' bounds taken in so far ([`Styles::bound`]).
    pub(super) fn bounds(&self) -> &Bounds {
        &self.bounds
    }

    /// As the moved values are written by `motion`: positions shifted by its scale (a change of
    /// unit), with at least the digits of a step of [`STEP_OF_DIAGONAL`] of the moved cloud's
    /// diagonal (decimals, or in exponent form significant digits, for the largest moved value);
    /// normals with at least six decimals.
    pub(super) fn for_writing(self, motion: &Motion) -> Self {
        let (diagonal, largest) = (self.bounds.diagonal(motion), self.bounds.largest_moved(motion));
        let mut position = self.position.scaled(motion.scale());
        let step = diagonal * STEP_OF_DIAGONAL;
        if step.is_finite() && step > 0.0 && largest.is_finite() {
            if position.exponent {
                // significant digits whose last reaches the step at the largest value: from the
                // largest's leading digit down to the step's
                let digits =
                    (largest.log10().floor() - step.log10().floor() + 1.0).clamp(1.0, MAX_DECIMALS as f64) as u32;
                position.significant = position.significant.max(digits);
                position.decimals = position.decimals.max(digits - 1);
            } else if let Some(d) = decimals_for_step(step) {
                position = position.at_least(d);
            }
        }
        Self { position, normal: self.normal.at_least(6), bounds: self.bounds }
    }
}

/// The fewest decimals whose step is at most `step` (none for a step that is not finite and
/// positive: a single point, no point).
fn decimals_for_step(step: f64) -> Option<u32> {
    (step.is_finite() && step > 0.0).then(|| (-step.log10()).ceil().clamp(0.0, MAX_DECIMALS as f64) as u32)
}

/// The most decimals written: beyond 17 an `f64` has no more digits to give.
const MAX_DECIMALS: i64 = 17;

impl NumberStyle {
    /// Learns from one token (a number as the file wrote it).
    pub(super) fn learn(&mut self, token: &str) {
        let mantissa = match token.find(['e', 'E']) {
            Some(i) => {
                self.exponent = true;
                self.exponent_upper |= token.as_bytes()[i] == b'E';
                let exponent = &token[i + 1..];
                self.exponent_plus |= exponent.starts_with('+');
                let digits = exponent.trim_start_matches(['+', '-']).len().min(4) as u32;
                self.exponent_digits = self.exponent_digits.max(digits);
                &token[..i]
            }
            None => {
                self.plain = true;
                token
            }
        };
        let decimals = mantissa.split_once('.').map_or(0, |(_, frac)| frac.len().min(MAX_DECIMALS as usize) as u32);
        self.decimals = self.decimals.max(decimals);
        self.varied |= *self.first_decimals.get_or_insert(decimals) != decimals;
        let digits = mantissa.bytes().filter(u8::is_ascii_digit).skip_while(|&b| b == b'0').count();
        self.significant = self.significant.max(digits.min(MAX_DECIMALS as usize) as u32);
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

    /// This style with a decimal point in every value (in exponent form, in the mantissa) and no
    /// digits trimmed: `48,-50` could be read as a number with a decimal comma, `48.0,-50.0` not.
    pub(super) fn with_point(self) -> Self {
        if self.exponent {
            let decimals = self.decimals.max(self.significant.saturating_sub(1)).max(1);
            Self { plain: false, decimals, ..self }
        } else {
            Self { decimals: self.decimals.max(1), varied: false, ..self }
        }
    }

    /// Appends `v` in this style: with its decimals; in exponent form (`1.018757e+02`, the
    /// exponent as the file wrote its exponents) when the file used exponents only; as C's `%g`
    /// writes it with the file's most significant digits when it used both. A value that rounds
    /// to zero is written without a sign.
    pub(super) fn write(self, v: f64, out: &mut Vec<u8>) {
        let d = self.decimals as usize;
        let start = out.len();
        if !self.exponent && write_fixed(v, d, out) {
            if self.varied && d > 0 {
                // trailing zeros (and a bare point) left out (no "-0" to mend: write_fixed gives
                // a value that rounds to zero no sign)
                let end = start + trim_zeros_len(&out[start..]);
                out.truncate(end);
            }
            return;
        }
        let mut s = if !self.exponent {
            let s = format!("{v:.d$}");
            if self.varied {
                trim_zeros(s)
            } else {
                s
            }
        } else if self.plain {
            self.general(v)
        } else {
            self.with_exponent(&format!("{v:.d$e}"), false)
        };
        if s.starts_with('-') && s[1..].bytes().all(|b| matches!(b, b'0' | b'.')) {
            s.remove(0);
        }
        out.extend_from_slice(s.as_bytes());
    }

    /// `v` as `%g` writes it with this style's significant digits: in exponent form when its
    /// exponent is below -4 or not below those digits, else with the decimals they leave;
    /// trailing zeros left out.
    fn general(self, v: f64) -> String {
        let p = self.significant.max(1) as usize;
        let e = format!("{:.*e}", p - 1, v);
        let x: i32 = e.split_once('e').and_then(|(_, x)| x.parse().ok()).unwrap_or(0);
        if x < -4 || x >= p as i32 {
            return self.with_exponent(&e, true);
        }
        let d = (p as i32 - 1 - x).max(0) as usize;
        trim_zeros(format!("{v:.d$}"))
    }

    /// `e` (Rust's exponent form, `1.50e-3`) with its exponent written in this style (`e-03`),
    /// its mantissa's trailing zeros left out when `trim`.
    fn with_exponent(self, e: &str, trim: bool) -> String {
        let Some((mantissa, x)) = e.split_once('e') else { return e.to_string() };
        let mut s = if trim { trim_zeros(mantissa.to_string()) } else { mantissa.to_string() };
        s.push(if self.exponent_upper { 'E' } else { 'e' });
        let digits = x.trim_start_matches('-');
        if x.starts_with('-') {
            s.push('-');
        } else if self.exponent_plus || self.exponent_digits >= 2 {
            // (exponents padded to two digits are C's, whose positive ones have their '+')
            s.push('+');
        }
        for _ in digits.len()..self.exponent_digits as usize {
            s.push('0');
        }
        s.push_str(digits);
        s
    }
}

/// `s` (a number with a decimal point) without its fraction's trailing zeros, nor a point left
/// bare.
fn trim_zeros(mut s: String) -> String {
    s.truncate(trim_zeros_len(s.as_bytes()));
    s
}

/// The length of the number `s` without its fraction's trailing zeros and a point left bare
/// (all of it when it has no point).
fn trim_zeros_len(s: &[u8]) -> usize {
    if !s.contains(&b'.') {
        return s.len();
    }
    let mut end = s.len();
    while s[end - 1] == b'0' {
        end -= 1;
    }
    if s[end - 1] == b'.' {
        end -= 1;
    }
    end
}

/// Appends `line` with the byte ranges `edits` replaced by their values in `style`, every other
/// byte as it was. `edits` (a few per line) do not overlap; they are put in order here.
fn splice(line: &[u8], edits: &mut [(Range<usize>, f64, NumberStyle)], out: &mut Vec<u8>) {
    super::util::in_text_order(edits, |e| e.0.start);
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
        self.line_if(line, edits, &|_| true);
    }

    /// As [`Rewrite::line`] when `accept` takes the rewritten line; false (nothing written)
    /// otherwise.
    pub(super) fn line_if(
        &mut self,
        line: &str,
        edits: &mut [(Range<usize>, f64, NumberStyle)],
        accept: &dyn Fn(&[u8]) -> bool,
    ) -> bool {
        let start = line.as_ptr() as usize - self.bytes.as_ptr() as usize;
        let before = self.out.len();
        self.out.extend_from_slice(&self.bytes[self.copied..start]);
        let at = self.out.len();
        splice(line.as_bytes(), edits, &mut self.out);
        if !accept(&self.out[at..]) {
            self.out.truncate(before);
            return false;
        }
        self.copied = start + line.len();
        true
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
        // numbers of one number of decimals: padded to them
        let mut padded = NumberStyle::default();
        for t in ["1.000", "-2.500", "3.125"] {
            padded.learn(t);
        }
        assert_eq!(written(padded, 1.0 / 3.0), "0.333");
        assert_eq!(written(padded, -0.0001), "0.000");
        assert_eq!(written(padded.scaled(1000.0), 1234.5678), "1235");
        assert_eq!(written(padded.scaled(0.0254), 1.0), "1.00000");
        assert_eq!(written(padded.scaled(1.0), 2.0), "2.000");
        assert_eq!(written(NumberStyle::default().at_least(6), 0.5), "0.500000");
        // numbers of varied decimals (not padded): up to the most, trailing zeros left out
        for t in ["1", "-2.5", "3.125", "4.0"] {
            s.learn(t);
        }
        assert_eq!(written(s, 1.0 / 3.0), "0.333");
        assert_eq!(written(s, -0.0001), "0");
        assert_eq!(written(s, -2.5), "-2.5");
        assert_eq!(written(s.scaled(0.0254), 1.0), "1");
        assert_eq!(written(s.scaled(1000.0), 1234.5678), "1235");
        assert_eq!(written(s, 1e20), "100000000000000000000");
        // exponents only: with the decimals, the exponent as written
        let mut e = NumberStyle::default();
        e.learn("1.500e-3");
        assert_eq!(written(e, 0.1 + 0.2), "3.000e-1");
        assert_eq!(written(e.scaled(1000.0), -1234.5678), "-1.235e3");
        assert_eq!(written(e, -1e-9), "-1.000e-9");
        // both, as %g writes them: the most significant digits (4 here), trailing zeros left out
        s.learn("1.5e-3");
        assert_eq!(written(s, 0.1 + 0.2), "0.3");
        assert_eq!(written(s.scaled(1000.0), -1234.5678), "-1235");
        assert_eq!(written(s, -1e-9), "-1e-9");
        assert_eq!(written(s, 12345.0), "1.234e4");
    }

    #[test]
    fn writes_as_c_and_cpp_streams_wrote() {
        // a PCL ascii PCD (C++ streams, 8 significant digits): plain, or exponents of two digits
        let mut pcl = NumberStyle::default();
        for t in ["0.0054215998", "0.11349", "-0.16884723", "9.9999997e-05"] {
            pcl.learn(t);
        }
        assert_eq!(written(pcl, 0.0184162723543), "0.018416272");
        assert_eq!(written(pcl, -0.5), "-0.5");
        assert_eq!(written(pcl, 1.234567891e-5), "1.2345679e-05");
        assert_eq!(written(pcl, 123456789.0), "1.2345679e+08");
        // an ASCII STL of a Windows program: exponents only, with a sign and three digits
        let mut stl = NumberStyle::default();
        stl.learn("1.000000E+002");
        stl.learn("-2.500000E-001");
        assert_eq!(written(stl, 100.0), "1.000000E+002");
        assert_eq!(written(stl, 0.5), "5.000000E-001");
        assert_eq!(written(stl, -3.0e-12), "-3.000000E-012");
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
        assert_eq!(written(NumberStyle { decimals: 3, ..Default::default() }, 1e20), "100000000000000000000.000");
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
