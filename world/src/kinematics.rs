//! How a command moves a robot in one tick (the control step: speeds per tick, turn rates in
//! radians per tick), before the world stops it short of obstacles.

use swarm::scenario::Kinematics;

/// Where the command would take a robot at `pose` = (x, y, heading) in one tick if nothing
/// were in the way: the displacement and the new heading (None: the heading follows the
/// displacement, for holonomic robots).
pub fn intended(k: &Kinematics, pose: [f64; 3], cmd: [f64; 2]) -> ([f64; 2], Option<f64>) {
    match *k {
        Kinematics::Holonomic => (cmd, None),
        // docs/hunting.md eqs. (2.8)-(2.10): x += v cos(phi) dt, y += v sin(phi) dt, then
        // phi += w dt, with dt = 1 tick.
        Kinematics::Unicycle { .. } => {
            let (v, w, phi) = (cmd[0], cmd[1], pose[2]);
            ([v * phi.cos(), v * phi.sin()], Some(wrap(phi + w)))
        }
    }
}

/// Whether a command respects the limits (speed `v_max`, and the turn rate for unicycles),
/// with a relative `tolerance` for floating-point rounding in the behaviours' clamps.
pub fn within_limits(k: &Kinematics, cmd: [f64; 2], v_max: f64, tolerance: f64) -> Limit {
    match *k {
        Kinematics::Holonomic => {
            if (cmd[0] * cmd[0] + cmd[1] * cmd[1]).sqrt() > v_max * (1.0 + tolerance) {
                Limit::TooFast
            } else {
                Limit::Within
            }
        }
        Kinematics::Unicycle { w_max } => {
            if cmd[0].abs() > v_max * (1.0 + tolerance) {
                Limit::TooFast
            } else if cmd[1].abs() > w_max * (1.0 + tolerance) {
                Limit::TurnTooFast
            } else {
                Limit::Within
            }
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Limit {
    Within,
    TooFast,
    TurnTooFast,
}

/// An angle in (-pi, pi].
pub fn wrap(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let r = a.rem_euclid(TAU);
    if r > PI {
        r - TAU
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unicycle_moves_along_its_heading_then_turns() {
        let k = Kinematics::Unicycle { w_max: 0.5 };
        let (d, h) = intended(&k, [0.0, 0.0, std::f64::consts::FRAC_PI_2], [2.0, 0.25]);
        assert!(d[0].abs() < 1e-12 && (d[1] - 2.0).abs() < 1e-12, "{d:?}");
        assert!((h.unwrap() - (std::f64::consts::FRAC_PI_2 + 0.25)).abs() < 1e-12);
        assert_eq!(within_limits(&k, [2.0, 0.6], 3.0, 1e-9), Limit::TurnTooFast);
        assert_eq!(within_limits(&k, [3.1, 0.1], 3.0, 1e-9), Limit::TooFast);
        assert_eq!(within_limits(&k, [-3.0, -0.5], 3.0, 1e-9), Limit::Within);
        let (d, h) = intended(&Kinematics::Holonomic, [1.0, 1.0, 0.3], [3.0, 4.0]);
        assert_eq!((d, h), ([3.0, 4.0], None));
    }

    #[test]
    fn wrap_stays_in_range() {
        for a in [-10.0, -3.2, -1.0, 0.0, 3.2, 7.0, 100.0] {
            let w = wrap(a);
            assert!(
                w > -std::f64::consts::PI && w <= std::f64::consts::PI,
                "{a} -> {w}"
            );
            assert!(
                ((a - w) / std::f64::consts::TAU).fract().abs() < 1e-9
                    || ((a - w) / std::f64::consts::TAU).fract().abs() > 1.0 - 1e-9
            );
        }
    }
}
