//! Kernels of the multi-target search paper (BSOA + TPEPSO; docs/search.md) and of its
//! baselines (SVF, EPSO, ARBA), pure functions with their unit tests. The search scenario
//! (issue 3) wires them into a behaviour; see `NOTES.md` beside this file for every choice made
//! where the paper is silent.

pub mod arba;
pub mod bsoa;
pub mod calibration;
pub mod estimator;
pub mod subgroup;
pub mod svf;
pub mod tpepso;

#[cfg(test)]
mod testkit;

use agent::kernels::virtual_force;
use serde::{Deserialize, Serialize};

/// Every kernel's tunables in one place (each section defaults to the
/// paper's values or the spec's suggested defaults).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// Eq. (5) and the roaming rule.
    pub virtual_force: virtual_force::Params,
    /// Eq. (33) signal model and eq. (6) calibration.
    pub calibration: calibration::Params,
    /// Eqs. (7)-(10) target position estimate.
    pub estimator: estimator::Params,
    /// Eq. (11) TPEPSO / EPSO.
    pub tpepso: tpepso::Params,
    /// ARBA, the bat-algorithm baseline (every value an assumption; arba.rs).
    pub arba: arba::Params,
    /// BSOA, eqs. (12)-(22) and Table 2 (includes the boundary scan).
    pub bsoa: bsoa::Params,
    /// SVF baseline.
    pub svf: svf::Params,
    /// Eqs. (2)-(3) and the closed-loop adjustment.
    pub subgroup: subgroup::Params,
}

impl Params {
    /// Checks that the physical constants repeated across sections agree
    /// (V_max, L_B, L_T). Returns the first mismatch.
    pub fn check_consistency(&self) -> Result<(), String> {
        let v = [
            ("virtual_force.v_max", self.virtual_force.v_max),
            ("tpepso.v_max", self.tpepso.v_max),
            ("arba.v_max", self.arba.v_max),
            ("bsoa.v_max", self.bsoa.v_max),
            ("svf.v_max", self.svf.v_max),
        ];
        let lb = [
            ("virtual_force.l_b", self.virtual_force.l_b),
            ("bsoa.l_b", self.bsoa.l_b),
            ("svf.l_b", self.svf.l_b),
        ];
        let lt = [
            ("calibration.l_t", self.calibration.l_t),
            ("bsoa.l_t", self.bsoa.l_t),
        ];
        for group in [&v[..], &lb[..], &lt[..]] {
            for (name, val) in &group[1..] {
                if *val != group[0].1 {
                    return Err(format!(
                        "{name} = {val} but {} = {}",
                        group[0].0, group[0].1
                    ));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::de::value::{Error, MapDeserializer};

    #[test]
    fn defaults_are_consistent() {
        assert_eq!(Params::default().check_consistency(), Ok(()));
        let mut p = Params::default();
        p.svf.v_max = 5.0;
        assert!(p.check_consistency().is_err());
        let mut p = Params::default();
        p.arba.v_max = 5.0;
        assert!(p.check_consistency().unwrap_err().contains("arba.v_max"));
    }

    #[test]
    fn unknown_fields_are_rejected_and_missing_ones_default() {
        let de = MapDeserializer::<_, Error>::new(vec![("g_max", 4u64)].into_iter());
        let p = subgroup::Params::deserialize(de).unwrap();
        assert_eq!((p.g_max, p.i_min), (4, 1.0));
        let de = MapDeserializer::<_, Error>::new(vec![("gmax", 4u64)].into_iter());
        assert!(subgroup::Params::deserialize(de).is_err());
        let de = MapDeserializer::<_, Error>::new(vec![("omega", 0.4f64)].into_iter());
        assert!(tpepso::Params::deserialize(de).is_err());
    }
}
