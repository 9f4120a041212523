//! A set of LAS classification codes ([`Classes`]), what [`super::ReadOptions::classes`] keeps
//! of a LAS or LAZ file: the ASPRS codes 0 to 255 (2 ground, 3-5 vegetation, 6 building, 7 low
//! noise, 9 water, 18 high noise, ...). In JS and JSON a list of integers.

use serde::de::Error as _;

/// A set of classification codes, 0 to 255 (a bit each). Never empty when read from a list.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Classes([u64; 4]);

impl Classes {
    /// The set of `codes`.
    pub fn of(codes: impl IntoIterator<Item = u8>) -> Self {
        let mut set = Self::default();
        for c in codes {
            set.insert(c);
        }
        set
    }

    /// Adds `code` to the set.
    pub fn insert(&mut self, code: u8) {
        self.0[usize::from(code >> 6)] |= 1 << (code & 63);
    }

    /// Whether `code` is in the set.
    pub fn has(&self, code: u8) -> bool {
        self.0[usize::from(code >> 6)] & (1 << (code & 63)) != 0
    }

    /// The codes in the set, ascending.
    pub fn codes(&self) -> impl Iterator<Item = u8> + '_ {
        (0..=255u8).filter(|c| self.has(*c))
    }

    /// The codes as a list for messages: `2, 6`.
    pub fn list(&self) -> String {
        self.codes().map(|c| c.to_string()).collect::<Vec<_>>().join(", ")
    }
}

impl serde::Serialize for Classes {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.codes())
    }
}

impl<'de> serde::Deserialize<'de> for Classes {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let codes = Vec::<u8>::deserialize(d)?;
        if codes.is_empty() {
            return Err(D::Error::custom(
                "classes: an empty list keeps no point (leave classes unset to keep every point)",
            ));
        }
        Ok(Self::of(codes))
    }
}

#[cfg(test)]
mod tests {
    use super::Classes;

    #[test]
    fn a_set_holds_its_codes_and_reads_from_a_list() {
        let set = Classes::of([0, 2, 63, 64, 255]);
        assert!(set.has(0) && set.has(2) && set.has(63) && set.has(64) && set.has(255));
        assert!(!set.has(1) && !set.has(65) && !set.has(254));
        assert_eq!(set.list(), "0, 2, 63, 64, 255");
        let read: Classes = serde_json::from_str("[6, 2, 2]").unwrap();
        assert_eq!(read, Classes::of([2, 6]));
        assert_eq!(serde_json::to_string(&read).unwrap(), "[2,6]");
        assert!(serde_json::from_str::<Classes>("[]").unwrap_err().to_string().contains("keeps no point"));
        assert!(serde_json::from_str::<Classes>("[256]").is_err());
        assert!(serde_json::from_str::<Classes>("[-1]").is_err());
        assert!(serde_json::from_str::<Classes>("2").is_err());
    }
}
