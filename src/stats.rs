//! Order statistics shared by the stages.

/// The median of `v` (its upper middle for an even count; `None` when empty), reordering it.
pub(crate) fn median(v: &mut [f64]) -> Option<f64> {
    let k = v.len() / 2;
    (!v.is_empty()).then(|| *v.select_nth_unstable_by(k, f64::total_cmp).1)
}

#[cfg(test)]
mod tests {
    #[test]
    fn median_of_odd_even_and_empty_lists() {
        assert_eq!(super::median(&mut [3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(super::median(&mut [4.0, 1.0, 3.0, 2.0]), Some(3.0));
        assert_eq!(super::median(&mut []), None);
    }
}
