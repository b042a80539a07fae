//! Every number the formation kernels use, with where it comes from. The paper (spec section 3)
//! publishes the world (24 x 24 box, 9 robots of radius 1, 2 obstacles of radius 2) and nothing
//! of the controller (V_p, a, tau, K_a, epsilon, the ORCA horizon): those are our calibration
//! choices, made so that one step moves about 0.25 units (spec 3: "V_p tau ~ 0.2-0.3"), and are
//! named here so that a scenario file can override each of them.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// How the obstacle constraint C2 is imposed on the targets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ObstacleConstraint {
    /// The paper's implemented form, eqs. (11)-(12): the target lies outside the axis-aligned
    /// square of half-side r_o + r around the obstacle centre (conservative: it implies (10)).
    #[default]
    Square,
    /// The exact form, eq. (10): ||q_j - o_m|| >= r_o + r.
    Circle,
}

/// Which reading of the transform, eq. (5), the parameters (alpha, d, theta) mean (spec 6 item 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum TransformReading {
    /// The paper as printed, eqs. (5), (6), (8): q = alpha s + d + s r(theta) with
    /// r(theta) = R(theta) - I, i.e. q = (alpha - 1) s + R(theta) s + d. Chosen as the default:
    /// Table 2's (alpha, d, r) values and Table 3's theta ranges are in this parameterisation.
    #[default]
    Literal,
    /// The conventional similarity q = alpha R(theta) s + d (alpha is then the true scale).
    Similarity,
}

/// Hungarian solves a node of the corner bound makes: its 4 corners, the centre (bound 4) and
/// the incumbent's midpoint.
pub const CORNER_SOLVES_PER_NODE: f64 = 6.0;

/// How the optimiser bounds the assignment's part of the objective over a node.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum OptimiserBound {
    /// The alignment polygon (alignment.rs): the optimal assignment depends only on the
    /// direction of the transform matrix, so H's vertices, traced once by the Hungarian method,
    /// give every node an exact assignment bound without a solve of its own. [chosen] the
    /// default: the same optimum, far fewer solves (docs/formation.md 9, "The alignment
    /// polygon").
    #[default]
    Polygon,
    /// Interval corners and centre duals (optimise.rs bounds 1-2 and 4): five to six Hungarian
    /// solves a node. Kept to measure against.
    Corners,
}

/// The pattern optimiser's search domain and stopping rule (the paper gives none of them).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct OptimiserParams {
    /// Search range of the "scale parameter" alpha. Chosen: \[0.5, 2.0\], wide enough for the
    /// paper's optima (0.83 to 1.13, Table 2) and for the separation bound (lambda >= ~1.02
    /// for our templates).
    pub alpha_range: [f64; 2],
    /// Search range of theta in radians. \[-pi, pi\] is the proposed model (free rotation); the
    /// baseline of ref. \[10\] is \[0, 0\]; section 3.4 restricts it (Table 3).
    pub theta_range: [f64; 2],
    /// Absolute optimality gap at which the branch-and-bound stops (squared units).
    pub gap_abs: f64,
    /// Relative optimality gap (of the incumbent cost) at which the branch-and-bound stops.
    /// The stop rule is: upper - lower <= max(gap_abs, gap_rel * upper).
    pub gap_rel: f64,
    /// Node budget: when it is spent the solver stops and reports the gap it has proved.
    pub max_nodes: usize,
    /// The assignment bound.
    pub bound: OptimiserBound,
    /// Hungarian solves the alignment polygon may make (`bound = "polygon"`); past them its
    /// open arcs stay open, which keeps every bound valid but looser. [chosen] 100 000: the
    /// 9-robot H has a few dozen vertices, 100 random starts a few thousand.
    pub max_solves: usize,
    /// Operations the polygon's solves may spend (a cold n x n solve counts n^3, a warm one
    /// n^2 for the cost matrix and for each row it augments). [chosen] 1e18: unlimited;
    /// the relayed plans of 100 and 500 robots set it from `replan.max_work`.
    pub max_work: f64,
    /// Warm-start the polygon's Hungarian solves from the neighbouring direction's assignment
    /// and column potentials (hungarian.rs `solve_warm_with`): the same vertices, fewer rows
    /// augmented. [chosen] true; false for the cold solves to measure against.
    pub warm_start: bool,
}

impl OptimiserParams {
    /// Spend at most `work` operations, counting n^3 for one cold n x n Hungarian solve: the
    /// corner bound makes [`CORNER_SOLVES_PER_NODE`] cold solves a node, so its node budget is
    /// work / (6 n^3); the polygon counts its solves' actual work (warm ones augment few rows)
    /// and its nodes, a few O(n) passes each, are bounded by `max_nodes` only.
    pub fn set_work_budget(&mut self, work: f64, n: usize, max_nodes: usize) {
        match self.bound {
            OptimiserBound::Corners => {
                let node = CORNER_SOLVES_PER_NODE * (n.max(1) as f64).powi(3);
                self.max_nodes = ((work / node) as usize).clamp(1, max_nodes);
            }
            OptimiserBound::Polygon => {
                self.max_work = work;
                self.max_nodes = max_nodes;
            }
        }
    }
}

impl Default for OptimiserParams {
    fn default() -> Self {
        Self {
            alpha_range: [0.5, 2.0],
            theta_range: [-PI, PI],
            gap_abs: 1e-3,
            gap_rel: 1e-3,
            max_nodes: 400_000,
            bound: OptimiserBound::Polygon,
            max_solves: 100_000,
            max_work: 1e18,
            warm_start: true,
        }
    }
}

/// The formation scenario's world and controller numbers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FormationParams {
    /// Lower-left corner of the application area (X_min, Y_min). The paper's 24 x 24 square
    /// (section 3.1) has no published origin; we put it at (0, 0).
    pub box_min: [f64; 2],
    /// Upper-right corner of the area (X_max, Y_max) = (24, 24), section 3.1.
    pub box_max: [f64; 2],
    /// Robot radius r = 1 (section 3.1).
    pub robot_radius: f64,
    /// Obstacle radius r_o = 2 (section 3.1).
    pub obstacle_radius: f64,
    /// Obstacle centres. Unpublished; chosen mid-box (spec 7 step 1), off the diagonal so the
    /// un-optimised pattern can hit them (the Fig. 6 analogue).
    pub obstacle_centres: Vec<[f64; 2]>,
    /// Extra spacing added to eq. (13)'s 2r: targets touching at exactly 2r let robots parked
    /// within epsilon overlap (spec 6 item 7). Chosen 0.2.
    pub separation_margin: f64,
    /// Extra clearance added to eq. (10)/(12)'s r_o + r for the targets. Chosen 0.1.
    pub obstacle_margin: f64,
    /// Which form of constraint C2 the optimiser imposes.
    pub obstacle_constraint: ObstacleConstraint,
    /// Which reading of eq. (5) the parameters use.
    pub transform_reading: TransformReading,
    /// Maximum speed V_p (eq. 16, 24). Unpublished; chosen 1 unit/s.
    pub max_speed: f64,
    /// Maximum acceleration a (eq. 24), units/s^2; None drops the limit. Chosen 4, so that
    /// a tau = V_p: a robot can stop (or reach full speed) in one step, which keeps v = 0 inside
    /// the feasible set AV_i and so keeps ORCA's obstacle half-planes satisfiable.
    pub max_accel: Option<f64>,
    /// Sides of the regular polygon circumscribing the acceleration disc ||v - v_i|| <= a tau,
    /// which the linear program takes as half-planes (it has only one disc, the speed one).
    pub accel_polygon_sides: usize,
    /// Step tau of eqs. (23), (27), seconds. Chosen 0.25 (so V_p tau = 0.25 units).
    pub time_step: f64,
    /// ORCA time horizon against robots (eq. 18's tau, which the paper reuses for the step);
    /// chosen 2 s, spec 3's suggestion of 2-5 s at V_p ~ 1.
    pub time_horizon: f64,
    /// ORCA time horizon against obstacles (RVO2 keeps a separate one; the paper has none).
    /// Chosen 1 s: obstacles are static, a shorter horizon lets robots pass close by.
    pub obstacle_time_horizon: f64,
    /// When the ORCA half-planes have no common point, retry with the robots' horizon halved,
    /// down to one step, before the 3-D fallback (which then minimises the violation of the
    /// short-horizon half-planes: the collisions of the next steps, the ones that make
    /// overlaps). Not in the paper or RVO2 (false: the 3-D fallback on the full horizon).
    /// [chosen] false for the paper's 9 robots; the 100- and 500-robot scenarios set it (in
    /// their dense crowd the full-horizon fallback let robots overlap, docs/formation.md 9).
    pub shrink_horizon_when_infeasible: bool,
    /// Keep every robot inside its buffered Voronoi cell (Zhou, Wang, Bandyopadhyay, Schwager
    /// 2017; not in the paper or RVO2): against a robot at distance d in direction u the step
    /// may close at most half the gap, u . v tau <= (d - 2r) / 2, and against a static disc at
    /// most the whole gap. These half-planes hold at the same priority as the obstacles', so
    /// ORCA's 3-D fallback relaxes only its own half-planes: when both robots of a pair keep
    /// theirs their discs cannot overlap at the next step, whatever ORCA's fallback chose.
    /// v = 0 satisfies them all, and lies in the acceleration polygon when a tau >= V_p, so they
    /// never make the hard set empty. [chosen] true: 500 robots overlapped in ORCA's fallback
    /// (docs/formation.md 9); false gives ORCA alone.
    pub buffered_cells: bool,
    /// Clearance the buffered cells keep beyond 2r (and r + r_o), against rounding: a gap
    /// smaller than this is treated as closed (the step may not shrink it). Chosen 1e-6.
    pub cell_slack: f64,
    /// Keep the step inside the box (walls.rs): against each wall within 1.5 steps, the step
    /// may close at most the gap less `cell_slack`. Not in the paper (its box is only the
    /// targets' constraint C1). [chosen] true: without it ORCA, blind to the walls, kept
    /// choosing a step the world refused, and robots sliding along a wall to slots C1 allows
    /// at r from it stopped for good (docs/formation.md 9, disc-big); false gives the paper's
    /// ORCA, walls enforced only by the world.
    pub wall_half_planes: bool,
    /// Neighbours farther than this are left out of ORCA. The paper intersects over all robots;
    /// robots farther than 2r + 2 V_p tau_h = 6 cannot collide within the horizon, so 10 leaves
    /// out nobody who matters.
    pub neighbour_dist: f64,
    /// Gain K_a of eq. (16): the speed falls linearly to 0 within K_a of the target. Chosen 1.
    pub k_a: f64,
    /// Arrival tolerance epsilon: the formation is complete when every robot is within it of
    /// its assigned target. Chosen 0.05 (spec 3 guesses 0.05-0.1).
    pub epsilon: f64,
    /// Iteration cap of the controller loop (spec 7 step 4 suggests 1000).
    pub max_iterations: usize,
    /// The pattern optimiser's domain and stopping rule.
    pub optimiser: OptimiserParams,
}

impl Default for FormationParams {
    fn default() -> Self {
        Self {
            box_min: [0.0, 0.0],
            box_max: [24.0, 24.0],
            robot_radius: 1.0,
            obstacle_radius: 2.0,
            obstacle_centres: vec![[9.0, 14.0], [15.0, 9.0]],
            separation_margin: 0.2,
            obstacle_margin: 0.1,
            obstacle_constraint: ObstacleConstraint::Square,
            transform_reading: TransformReading::Literal,
            max_speed: 1.0,
            max_accel: Some(4.0),
            accel_polygon_sides: 16,
            time_step: 0.25,
            time_horizon: 2.0,
            obstacle_time_horizon: 1.0,
            shrink_horizon_when_infeasible: false,
            buffered_cells: true,
            cell_slack: 1e-6,
            wall_half_planes: true,
            neighbour_dist: 10.0,
            k_a: 1.0,
            epsilon: 0.05,
            max_iterations: 1000,
            optimiser: OptimiserParams::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_round_trip_through_toml_and_fill_defaults() {
        let p = FormationParams::default();
        let text = toml::to_string(&p).unwrap();
        let back: FormationParams = toml::from_str(&text).unwrap();
        assert_eq!(p, back);
        let partial: FormationParams =
            toml::from_str("max_speed = 2.0\nobstacle_constraint = \"circle\"\n").unwrap();
        assert_eq!(partial.max_speed, 2.0);
        assert_eq!(partial.obstacle_constraint, ObstacleConstraint::Circle);
        assert_eq!(partial.k_a, 1.0);
    }
}
