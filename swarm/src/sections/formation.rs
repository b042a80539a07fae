//! The formation paper's scenario section (`[formation]`, docs/formation.md) and what its world
//! mission and its behaviour share: the pattern template (data, so a user can draw their own),
//! how the pattern is chosen and reassigned, the arrival tolerance, and the layout of the
//! robots' Action `report`.
//!
//! The box is the arena, the obstacles are the arena's discs (`[[arena.discs]]`), the robot
//! radius is `robot.radius` and the speed limit V_p is `robot.v_max / time_step` (v_max is per
//! tick): one source for each number.

use serde::{Deserialize, Serialize};

/// How the pattern (alpha, d, theta) is chosen.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum PatternChoice {
    /// Eq. (14) with the rotation theta (the paper's model), theta in the kernels' range.
    #[default]
    Optimise,
    /// The no-rotation model of ref. \[10\] (theta fixed at 0): the paper's baseline.
    NoRotation,
    /// The parameters of `transform` as they are (Table 2's perturbed sets; large swarms).
    Fixed,
}

/// How robots are reassigned to slots while they move.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Reassignment {
    /// The coordinator solves eq. (15) (Hungarian) every tick on the positions it heard and
    /// broadcasts the assignment with an epoch (the paper's per-step reassignment, section 2.1).
    #[default]
    PerStep,
    /// The assignment of the pattern's solution is kept (section 3.2's one-shot comparison).
    OneShot,
    /// Beyond the paper: no coordinator after the plan; neighbours swap slots pairwise with a
    /// handshake (agent/src/formation/swaps.rs).
    Swaps,
}

/// Only formation scenarios have one, so other scenarios' resolved files (and recordings)
/// are unchanged.
impl crate::plugin::Section for FormationSection {
    const NAME: &'static str = "formation";
}

/// The `[formation]` section.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct FormationSection {
    /// Name of the pattern (for reports): "C", "n", "r" or the user's own.
    pub template_name: String,
    /// The template S, one point per robot (any origin: the optimiser centres it). Empty: the
    /// built-in letter named by `template_name` (agent/src/formation/template.rs).
    pub template: Vec<[f64; 2]>,
    /// How the pattern is chosen.
    pub pattern: PatternChoice,
    /// [alpha, d_1, d_2, theta] for `pattern = "fixed"` (the reading of eq. (5) is the
    /// kernels' `transform_reading`, literal by default).
    pub transform: [f64; 4],
    /// Reassignment while moving.
    pub reassignment: Reassignment,
    /// Where run.svg draws the un-optimised pattern (Fig. 6): the template at alpha = 1,
    /// theta = 0, translated so its centroid is here. [chosen] the box centre of the paper's
    /// 24 x 24 square.
    pub unoptimised_centre: [f64; 2],
    /// Arrival tolerance epsilon (the paper's value is unpublished): the formation is complete
    /// when every live robot is within epsilon of its assigned slot. [chosen] 0.05.
    pub epsilon: f64,
    /// A robot not heard for this many ticks is taken as lost: the coordinator re-plans the
    /// pattern for the robots left (its last position becomes an obstacle), and ORCA forgets
    /// it. [chosen] 10 ticks (2.5 s at tau = 0.25).
    pub lost_after_ticks: u32,
    /// The run ends when the formation is complete (else at run.max_ticks).
    pub end_when_formed: bool,
    /// The behaviour's own parameters (agent::formation::FormationParams: controller, ORCA,
    /// optimiser), validated by the agent crate. The box, radius, obstacles and V_p are
    /// derived from the arena and robot sections and written here on resolve.
    pub kernels: toml::Table,
}

impl Default for FormationSection {
    fn default() -> Self {
        FormationSection {
            template_name: "C".into(),
            template: Vec::new(),
            pattern: PatternChoice::Optimise,
            transform: [1.0, 0.0, 0.0, 0.0],
            reassignment: Reassignment::PerStep,
            unoptimised_centre: [12.0, 12.0],
            epsilon: 0.05,
            lost_after_ticks: 10,
            end_when_formed: true,
            kernels: toml::Table::new(),
        }
    }
}

/// Display states of the formation behaviour: moving is `frames::STATE_DEFAULT` (0).
pub const STATE_IN_PLACE: u32 = 1;
/// The robot is the coordinator (lowest id it hears).
pub const STATE_COORDINATOR: u32 = 2;

/// `report[2]` when the robot has no slot yet.
pub const REPORT_NO_SLOT: f64 = -1.0;
/// `report[2]` on the tick the coordinator solved the pattern: the report is then
/// [gap, optimiser wall seconds, REPORT_PLAN, branch-and-bound nodes].
pub const REPORT_PLAN: f64 = -2.0;
/// `report[0]` (the gap) of a plan report when the optimiser found no feasible placement of
/// the pattern (box, obstacles, separation) and the plan fell back to `formation.transform`:
/// the summary says "NO FEASIBLE PATTERN" (a proven gap is never negative).
pub const REPORT_GAP_INFEASIBLE: f64 = -1.0;
/// `report[2]` on the tick after a plan: [alpha, theta, REPORT_PLAN_SHAPE, plan epoch].
pub const REPORT_PLAN_SHAPE: f64 = -3.0;
/// `report[2]` two ticks after a plan: [d_1, d_2, REPORT_PLAN_SHIFT, plan epoch].
pub const REPORT_PLAN_SHIFT: f64 = -4.0;
// Otherwise the report is [slot x, slot y, slot index, plan epoch].

/// Gap between neighbouring points of the built-in letters (template units): 2r + 0.148 at
/// r = 1, so the separation constraint (2r + margin) needs a scale of only ~1.02.
pub const LETTER_SPACING: f64 = 2.148;

/// The built-in template `name` with `n` points. "C": for n = 9 the 270-degree arc of radius
/// 3.7 opening to +x that spec 7 suggests (chord 2.148); for more robots a thick C, arcs of
/// radius 3.7, 5.9, 8.1, ... (2.2 apart) filled from the inside, each with points about
/// LETTER_SPACING apart (the outermost one spread over the whole arc). "n" and "r": the
/// 9-point letters of section 3.4 (agent/src/formation/template.rs uses these).
pub fn builtin_template(name: &str, n: usize) -> Result<Vec<[f64; 2]>, String> {
    match name {
        "C" => Ok(letter_c(n)),
        "n" | "r" if n != 9 => Err(format!(
            "the built-in letter {name:?} has 9 points, not {n}: give formation.template"
        )),
        "n" => Ok(vec![
            [0.0, 0.0],
            [0.0, 2.2],
            [0.0, 4.4],
            [
                2.8 + 2.8 * 135f64.to_radians().cos(),
                4.4 + 2.8 * 135f64.to_radians().sin(),
            ],
            [
                2.8 + 2.8 * 90f64.to_radians().cos(),
                4.4 + 2.8 * 90f64.to_radians().sin(),
            ],
            [
                2.8 + 2.8 * 45f64.to_radians().cos(),
                4.4 + 2.8 * 45f64.to_radians().sin(),
            ],
            [5.6, 4.4],
            [5.6, 2.2],
            [5.6, 0.0],
        ]),
        "r" => Ok(vec![
            [0.0, 0.0],
            [0.0, 2.2],
            [0.0, 4.4],
            [0.0, 6.6],
            [0.0, 8.8],
            [2.0, 9.8],
            [4.2, 10.0],
            [6.2, 9.2],
            [7.8, 7.6],
        ]),
        _ => Err(format!(
            "{name:?} is not a built-in letter (\"C\", \"n\", \"r\"): give formation.template"
        )),
    }
}

fn letter_c(n: usize) -> Vec<[f64; 2]> {
    let (start, sweep) = (45f64.to_radians(), 270f64.to_radians());
    let arc = |radius: f64, k: usize, count: usize| {
        let a = if count == 1 {
            start + 0.5 * sweep
        } else {
            start + sweep * k as f64 / (count - 1) as f64
        };
        [radius * a.cos(), radius * a.sin()]
    };
    if n <= 9 {
        // The 9-point C (every 33.75 degrees); fewer robots take its first n points.
        return (0..n)
            .map(|k| {
                let a = (45.0 + 33.75 * k as f64).to_radians();
                [3.7 * a.cos(), 3.7 * a.sin()]
            })
            .collect();
    }
    let mut points = Vec::with_capacity(n);
    let mut radius = 3.7;
    while points.len() < n {
        // Points of this arc: chords of at least LETTER_SPACING.
        let step = 2.0 * (LETTER_SPACING / (2.0 * radius)).asin();
        let fits = (sweep / step).floor() as usize + 1;
        let count = fits.min(n - points.len());
        // A partial outer arc is spread over the whole sweep (its chords only grow).
        points.extend((0..count).map(|k| arc(radius, k, count)));
        radius += 2.2;
    }
    points
}

impl FormationSection {
    /// The key [`Self::template_points`] reads, so that its error names what the user wrote:
    /// `formation.template` when the points are given, else `formation.template_name`.
    pub fn template_key(&self) -> &'static str {
        if self.template.is_empty() {
            "formation.template_name"
        } else {
            "formation.template"
        }
    }

    /// The template S for `n` robots: `template` when given, else the built-in letter.
    pub fn template_points(&self, n: usize) -> Result<Vec<[f64; 2]>, String> {
        if self.template.is_empty() {
            builtin_template(&self.template_name, n)
        } else if self.template.len() != n {
            Err(format!(
                "has {} points but run.robots = {n}: one point per robot",
                self.template.len()
            ))
        } else {
            Ok(self.template.clone())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn min_spacing(p: &[[f64; 2]]) -> f64 {
        let mut best = f64::INFINITY;
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                best = best.min(((p[i][0] - p[j][0]).powi(2) + (p[i][1] - p[j][1]).powi(2)).sqrt());
            }
        }
        best
    }

    #[test]
    fn the_letter_c_has_n_points_at_least_the_letter_spacing_apart() {
        let c9 = builtin_template("C", 9).unwrap();
        // Hand-computed: the first point at 45 degrees on radius 3.7.
        let h = 3.7 * std::f64::consts::FRAC_1_SQRT_2;
        assert!((c9[0][0] - h).abs() < 1e-12 && (c9[0][1] - h).abs() < 1e-12);
        assert!((min_spacing(&c9) - 2.0 * 3.7 * 16.875f64.to_radians().sin()).abs() < 1e-12);
        for n in [10, 100, 500] {
            let c = builtin_template("C", n).unwrap();
            assert_eq!(c.len(), n);
            assert!(
                min_spacing(&c) >= LETTER_SPACING - 1e-9,
                "n {n}: {}",
                min_spacing(&c)
            );
        }
        assert!(builtin_template("n", 10).is_err());
        assert!(builtin_template("Z", 9).is_err());
        assert!(min_spacing(&builtin_template("n", 9).unwrap()) > 2.1);
        assert!(min_spacing(&builtin_template("r", 9).unwrap()) > 2.1);
    }
}
