//! Serde helper for a `u64` that must round-trip through TOML for every value.
//!
//! TOML integers are signed 64-bit, so `toml` cannot write a `u64` above `i64::MAX` (it failed
//! with `OutOfRange`, and `--seed 9223372036854775808` panicked). Such values are written as a
//! decimal string (`seed = "18446744073709551615"`); values that fit stay plain integers, so
//! every existing file reads and writes as before. Reading accepts either form.

use serde::de::{self, Deserializer, Visitor};
use serde::Serializer;

pub fn serialize<S: Serializer>(v: &u64, s: S) -> Result<S::Ok, S::Error> {
    match i64::try_from(*v) {
        Ok(i) => s.serialize_i64(i),
        Err(_) => s.serialize_str(&v.to_string()),
    }
}

pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
    d.deserialize_any(U64Visitor)
}

struct U64Visitor;

impl Visitor<'_> for U64Visitor {
    type Value = u64;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(
            f,
            "a whole number 0..={} (above {} as a decimal string)",
            u64::MAX,
            i64::MAX
        )
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<u64, E> {
        Ok(v)
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<u64, E> {
        u64::try_from(v).map_err(|_| E::invalid_value(de::Unexpected::Signed(v), &self))
    }

    fn visit_str<E: de::Error>(self, v: &str) -> Result<u64, E> {
        v.trim()
            .parse()
            .map_err(|_| E::invalid_value(de::Unexpected::Str(v), &self))
    }
}

#[cfg(test)]
mod tests {
    #[derive(serde::Serialize, serde::Deserialize, Debug, PartialEq)]
    struct T {
        #[serde(with = "super")]
        v: u64,
    }

    #[test]
    fn every_u64_round_trips_through_toml() {
        for v in [0, 1, i64::MAX as u64, i64::MAX as u64 + 1, u64::MAX] {
            let text = toml::to_string(&T { v }).unwrap();
            assert_eq!(toml::from_str::<T>(&text).unwrap(), T { v }, "{text}");
        }
        // Values that fit an i64 stay plain integers (existing files are unchanged).
        assert_eq!(toml::to_string(&T { v: 7 }).unwrap().trim(), "v = 7");
        assert_eq!(
            toml::to_string(&T { v: u64::MAX }).unwrap().trim(),
            "v = \"18446744073709551615\""
        );
    }

    #[test]
    fn negative_and_non_numbers_are_refused() {
        assert!(toml::from_str::<T>("v = -1").is_err());
        assert!(toml::from_str::<T>("v = \"x\"").is_err());
        assert!(toml::from_str::<T>("v = \"18446744073709551616\"").is_err());
    }
}
