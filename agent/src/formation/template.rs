//! Patterns as data (the paper's template S, one point per robot) and the transform of eq. (5)
//! that maps a template point s_j to a target q_j.
//!
//! The reading of eq. (5) (spec 6 item 3): as printed, q_j = alpha s_j + d + s_j r(theta) with
//! r(theta) = \[\[cos - 1, sin\], \[-sin, cos - 1\]\] acting on the row vector s_j (eq. 6),
//! which in column form is q = A s + d with A = \[\[a, -b\], \[b, a\]\], a = alpha - 1 + cos theta,
//! b = sin theta (eq. 8). The default, [`TransformReading::Literal`], is that; the alternative,
//! [`TransformReading::Similarity`], is a = alpha cos theta, b = alpha sin theta. Either way A is
//! a rotation times a scale lambda = sqrt(a^2 + b^2), which is all the optimiser needs.

use super::params::TransformReading;
use serde::{Deserialize, Serialize};
use swarm::geometry::Vec2;

/// A pattern template: the points S = \[s_1; ...; s_n\] (any origin; the optimiser centres them).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Template {
    /// The letter or name of the pattern, for reports.
    pub name: String,
    /// The template points, one per robot.
    pub points: Vec<[f64; 2]>,
}

impl Template {
    /// The template points as vectors.
    pub fn vectors(&self) -> Vec<Vec2> {
        self.points.iter().map(|p| Vec2::new(p[0], p[1])).collect()
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the template has no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Smallest distance between two template points (infinite for fewer than 2 points).
    pub fn min_spacing(&self) -> f64 {
        let v = self.vectors();
        let mut best = f64::INFINITY;
        for i in 0..v.len() {
            for j in i + 1..v.len() {
                best = best.min((v[i] - v[j]).norm());
            }
        }
        best
    }

    /// A 9-point letter of the scenario section's built-ins (`swarm::sections::formation`,
    /// the one place the letters are drawn).
    fn builtin(name: &str) -> Self {
        Self {
            name: name.into(),
            points: swarm::sections::formation::builtin_template(name, 9)
                .expect("the built-in letters have 9 points"),
        }
    }

    /// The letter C, as spec 7 step 2 suggests: 9 points on a 270 degree arc of radius 3.7
    /// opening to +x (from 45 to 315 degrees), chord spacing 2 * 3.7 * sin(16.875 deg) = 2.148.
    pub fn letter_c() -> Self {
        Self::builtin("C")
    }

    /// The letter n (section 3.4): two stems of 3 points 2.2 apart, 5.6 apart, joined by a
    /// half-circle arch of radius 2.8 whose 3 inner points are 45 degrees apart (chord 2.14).
    pub fn letter_n() -> Self {
        Self::builtin("n")
    }

    /// The letter r (section 3.4): a stem of 5 points 2.2 apart and a shoulder of 4 points
    /// arching right from its top (spacings 2.24, 2.21, 2.15, 2.26).
    pub fn letter_r() -> Self {
        Self::builtin("r")
    }

    /// The default templates by name ("C", "n", "r").
    pub fn by_name(name: &str) -> Option<Self> {
        match name {
            "C" => Some(Self::letter_c()),
            "n" => Some(Self::letter_n()),
            "r" => Some(Self::letter_r()),
            _ => None,
        }
    }
}

/// The pattern parameters of eq. (5): the "scale parameter" alpha, translation d, rotation theta.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    /// alpha (比例参数).
    pub alpha: f64,
    /// d = \[d_1, d_2\].
    pub d: [f64; 2],
    /// theta in radians.
    pub theta: f64,
}

impl Transform {
    /// The coefficients (a, b) of A = \[\[a, -b\], \[b, a\]\] under the reading (eq. 8).
    pub fn matrix(&self, reading: TransformReading) -> (f64, f64) {
        matrix(self.alpha, self.theta, reading)
    }

    /// q = A s + d: eq. (5) (component-wise, eq. 8).
    pub fn apply(&self, reading: TransformReading, s: Vec2) -> Vec2 {
        let (a, b) = self.matrix(reading);
        Vec2::new(a * s.x - b * s.y + self.d[0], b * s.x + a * s.y + self.d[1])
    }

    /// The targets q_1..q_n of a template (the paper's G* at the optimal parameters).
    pub fn targets(&self, reading: TransformReading, template: &Template) -> Vec<Vec2> {
        template
            .vectors()
            .into_iter()
            .map(|s| self.apply(reading, s))
            .collect()
    }

    /// The effective scale lambda = sqrt(a^2 + b^2) and rotation phi = atan2(b, a) (spec 2.1).
    pub fn scale_and_rotation(&self, reading: TransformReading) -> (f64, f64) {
        let (a, b) = self.matrix(reading);
        (a.hypot(b), b.atan2(a))
    }
}

/// (a, b) of the transform matrix for given alpha and theta (eq. 8 for the literal reading).
pub fn matrix(alpha: f64, theta: f64, reading: TransformReading) -> (f64, f64) {
    let (sin, cos) = theta.sin_cos();
    match reading {
        TransformReading::Literal => (alpha - 1.0 + cos, sin),
        TransformReading::Similarity => (alpha * cos, alpha * sin),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn literal_reading_matches_eq_8_componentwise() {
        // eq. (8): x_q = alpha x_s + d1 + x_s (cos - 1) - y_s sin,
        //          y_q = alpha y_s + d2 + x_s sin + y_s (cos - 1).
        let t = Transform {
            alpha: 1.0725,
            d: [3.369, 0.6924],
            theta: 0.1323,
        };
        let s = Vec2::new(2.0, -1.5);
        let q = t.apply(TransformReading::Literal, s);
        let (sn, cs) = t.theta.sin_cos();
        let x = t.alpha * s.x + t.d[0] + s.x * (cs - 1.0) - s.y * sn;
        let y = t.alpha * s.y + t.d[1] + s.x * sn + s.y * (cs - 1.0);
        assert!((q.x - x).abs() < 1e-12 && (q.y - y).abs() < 1e-12);
        // Spec 2.1: Table 2 row 1's optimum is a scale 1.0719 and a rotation 0.1234 rad.
        let (lambda, phi) = t.scale_and_rotation(TransformReading::Literal);
        assert!((lambda - 1.0719).abs() < 1e-4, "{lambda}");
        assert!((phi - 0.1234).abs() < 1e-4, "{phi}");
    }

    #[test]
    fn similarity_reading_is_scale_then_rotation() {
        let t = Transform {
            alpha: 2.0,
            d: [1.0, 1.0],
            theta: std::f64::consts::FRAC_PI_2,
        };
        let q = t.apply(TransformReading::Similarity, Vec2::new(1.0, 0.0));
        assert!((q - Vec2::new(1.0, 3.0)).norm() < 1e-12);
    }

    #[test]
    fn default_templates_have_nine_points_spaced_over_two() {
        for t in [
            Template::letter_c(),
            Template::letter_n(),
            Template::letter_r(),
        ] {
            assert_eq!(t.len(), 9, "{}", t.name);
            assert!(t.min_spacing() > 2.1, "{}: {}", t.name, t.min_spacing());
        }
        let c = Template::letter_c();
        assert!((c.min_spacing() - 2.0 * 3.7 * (16.875f64).to_radians().sin()).abs() < 1e-9);
    }
}
