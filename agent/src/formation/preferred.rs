//! The preferred velocity, eq. (16): towards the assigned target at the top speed V_p, slowing
//! linearly to 0 within K_a of it,
//! V_pref = V_p min(1, ||q - p|| / K_a) (q - p) / ||q - p||.

use swarm::geometry::Vec2;

/// Eq. (16). At the target (distance 0) the direction is undefined and the velocity is 0.
pub fn preferred_velocity(position: Vec2, target: Vec2, max_speed: f64, k_a: f64) -> Vec2 {
    let to_target = target - position;
    let distance = to_target.norm();
    if distance <= f64::EPSILON {
        return Vec2::zeros();
    }
    to_target * (max_speed * (distance / k_a).min(1.0) / distance)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn saturates_far_away_and_slows_within_k_a() {
        // 5 units away along +x with V_p = 2, K_a = 1: full speed 2 along +x.
        let v = preferred_velocity(Vec2::new(1.0, 1.0), Vec2::new(6.0, 1.0), 2.0, 1.0);
        assert!((v - Vec2::new(2.0, 0.0)).norm() < 1e-12);
        // 0.5 away along the diagonal with K_a = 2: speed 2 * 0.5 / 2 = 0.5.
        let d = Vec2::new(0.3, 0.4);
        let v = preferred_velocity(Vec2::zeros(), d, 2.0, 2.0);
        assert!((v - d).norm() < 1e-12, "{v:?}");
        assert_eq!(preferred_velocity(d, d, 2.0, 2.0), Vec2::zeros());
    }
}
