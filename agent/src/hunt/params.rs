//! Every tunable of the hunting kernels (thesis 003, chapters 2-3) in one struct, the
//! `[hunt.params]` section of a scenario file; it lives in `swarm::sections::hunt`, which the
//! world's hunt mission reads too. Units throughout: **km** for lengths (the
//! thesis's tables are in km on a 10 km x 10 km arena) and **minutes** for time, so speeds are
//! km/min and turn rates rad/min. Nearly none of these values is printed in the thesis
//! (docs/hunting.md section 6 and 12): each is marked [thesis] or [chosen] with the reason.

pub use swarm::sections::hunt::HuntParams;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_alpha_in_open_interval() {
        let p = HuntParams::default();
        assert!(
            (p.m1 + p.m2 + p.m3 - 1.0).abs() < 1e-12,
            "(3.9): m1+m2+m3 = 1"
        );
        assert!(p.alpha > 0.0 && p.alpha < 1.0, "(3.11): alpha in (0,1)");
        // r_s must lie inside every r_e the example uses (L_j up to 5).
        assert!(p.r_s < p.effective_range(5));
    }

    #[test]
    fn escape_defaults_mirror_the_world_side() {
        // The evader's escape lives in the world crate; its defaults must agree with these.
        let p = HuntParams::default();
        let e = world::mission::hunt_escape::EscapeParams::default();
        assert_eq!(p.evader_sensing_radius, e.sensing_radius);
        assert_eq!(p.encirclement_slowdown, e.encirclement_slowdown);
    }

    #[test]
    fn effective_range_shrinks_with_required_robots() {
        let p = HuntParams::default();
        assert!((p.effective_range(3) - 1.0).abs() < 1e-12);
        assert!((p.effective_range(5) - 0.6).abs() < 1e-12);
        assert!(p.effective_range(4) < p.effective_range(3));
    }

    #[test]
    fn empty_section_is_the_default_and_unknown_keys_are_rejected() {
        let p: HuntParams = toml::from_str("").unwrap();
        assert_eq!(p, HuntParams::default());
        let p: HuntParams = toml::from_str("alpha = 0.5").unwrap();
        assert_eq!(p.alpha, 0.5);
        assert!(toml::from_str::<HuntParams>("alfa = 0.5").is_err());
    }
}
