//! Optimal reciprocal collision avoidance, eqs. (17)-(26) (van den Berg, Guy, Lin, Manocha 2011,
//! the paper's ref. \[21\]): one half-plane of allowed velocities per neighbour, then the velocity
//! nearest the preferred one inside all of them, the speed disc and the acceleration limit.
//!
//! For robot i and a neighbour j (positions p, velocities v, radii r): the velocity obstacle of
//! eq. (18) is the set of relative velocities v_i - v_j that bring the discs into contact within
//! the horizon T, a cone from the origin around p_rel = p_j - p_i (the sign the paper slips on,
//! spec 2.5), truncated by the cut-off disc D(p_rel / T, R / T), R = r_i + r_j. u is the
//! smallest change of the relative velocity onto the obstacle's boundary (eq. 21), n the outward
//! normal there, and ORCA_ij = { v : (v - (v_i + c u)) . n >= 0 } (eq. 22) with responsibility
//! c = 1/2 against robots and c = 1 against static disc obstacles (treated as discs of radius
//! r_o with zero velocity, and their own horizon). Pairs already overlapping use the step in
//! place of T, so the half-plane asks to separate within one step.
//!
//! Choices where the paper is silent (spec 6 item 9): v^opt is the current velocity; the
//! acceleration disc ||v - v_i|| <= a tau of eq. (24) is the regular polygon circumscribing it
//! (so up to a tau / cos(pi / sides) in its corners); priorities, when the half-planes conflict:
//! the acceleration polygon always holds, obstacles (and the walls, [`super::walls`]) hold
//! unless they conflict with it, and the largest violation of the robots' half-planes is
//! minimised (the 3-D fallback of [`super::linear_program`]).

use super::linear_program::{select_velocity, HalfPlane, Selected, Selection};
use super::params::FormationParams;
use super::walls::wall_half_planes;
use swarm::geometry::Vec2;

/// A disc agent (or a static obstacle with zero velocity) as the Sense frame reports it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disc {
    /// Centre.
    pub position: Vec2,
    /// Current velocity.
    pub velocity: Vec2,
    /// Radius.
    pub radius: f64,
}

/// The ORCA half-plane that `me` keeps against `other` (eqs. 18, 21, 22). `responsibility` is
/// c, `horizon` the T of eq. (18), `time_step` the step used when the discs already overlap.
pub fn orca_half_plane(
    me: &Disc,
    other: &Disc,
    responsibility: f64,
    horizon: f64,
    time_step: f64,
) -> HalfPlane {
    let p_rel = other.position - me.position;
    let v_rel = me.velocity - other.velocity;
    let r = me.radius + other.radius;
    let dist2 = p_rel.norm_squared();
    let (u, n) = if dist2 > r * r {
        // From the cut-off disc's centre to the relative velocity.
        let w = v_rel - p_rel / horizon;
        let w2 = w.norm_squared();
        let along = w.dot(&p_rel);
        if along < 0.0 && along * along > r * r * w2 {
            // Nearest boundary point is on the cut-off arc.
            let wl = w2.sqrt();
            let n = w / wl;
            (n * (r / horizon - wl), n)
        } else {
            // Nearest boundary point is on a leg of the cone: the tangent through the origin.
            let leg = (dist2 - r * r).sqrt();
            let (dir, n) = if cross(p_rel, w) > 0.0 {
                let d = Vec2::new(p_rel.x * leg - p_rel.y * r, p_rel.x * r + p_rel.y * leg) / dist2;
                (d, Vec2::new(-d.y, d.x))
            } else {
                let d =
                    Vec2::new(p_rel.x * leg + p_rel.y * r, -p_rel.x * r + p_rel.y * leg) / dist2;
                (d, Vec2::new(d.y, -d.x))
            };
            (dir * v_rel.dot(&dir) - v_rel, n)
        }
    } else {
        // Overlapping: the cut-off disc of one step.
        let w = v_rel - p_rel / time_step;
        let wl = w.norm();
        let n = if wl > 1e-12 {
            w / wl
        } else if dist2 > 0.0 {
            -p_rel / dist2.sqrt()
        } else {
            Vec2::new(1.0, 0.0)
        };
        (n * (r / time_step - wl), n)
    };
    HalfPlane {
        point: me.velocity + u * responsibility,
        normal: n,
    }
}

fn cross(a: Vec2, b: Vec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// The half-planes circumscribing ||v - current|| <= reach with `sides` edges (eq. 24).
pub fn acceleration_polygon(current: Vec2, reach: f64, sides: usize) -> Vec<HalfPlane> {
    (0..sides)
        .map(|k| {
            let angle = std::f64::consts::TAU * k as f64 / sides as f64;
            let out = Vec2::new(angle.cos(), angle.sin());
            HalfPlane {
                point: current + out * reach,
                normal: -out,
            }
        })
        .collect()
}

/// The buffered-cell half-planes of `me` (see `FormationParams::buffered_cells`), on the
/// velocity: against robot j at distance d in direction u, u . v <= (d - 2r - slack) / (2 tau)
/// (each robot of the pair closes at most half the gap in one step; so
/// ||p_j' - p_i'|| >= u . (p_j' - p_i') >= d - (d - 2r) = 2r), and against a static obstacle
/// the whole gap, u . v <= (d - r - r_o - slack) / tau. r are the true radii: the discs' radii
/// less `margin` (ORCA's enlargement). Pairs that cannot close their gap at `max_speed` add
/// nothing. A gap already below the slack gives u . v <= 0 (never shrink it); an overlap (which
/// the cells prevent) asks to open it.
pub fn buffered_cell_half_planes(
    me: &Disc,
    robots: &[Disc],
    obstacles: &[Disc],
    margin: f64,
    params: &FormationParams,
) -> Vec<HalfPlane> {
    let tau = params.time_step;
    let reach = params.max_speed * tau;
    let mut out = Vec::new();
    let pairs = robots
        .iter()
        .map(|o| (o, 2.0))
        .chain(obstacles.iter().map(|o| (o, 1.0)));
    for (other, share) in pairs {
        let p_rel = other.position - me.position;
        let d = p_rel.norm();
        if d <= 1e-12 {
            continue;
        }
        let contact = (me.radius - margin) + (other.radius - margin);
        let gap = d - contact;
        // The step can close at most `reach` of it from this side.
        if gap / share > 1.5 * reach {
            continue;
        }
        let bound = if gap >= 0.0 {
            ((gap - params.cell_slack) / share).max(0.0) / tau
        } else {
            gap / share / tau
        };
        let u = p_rel / d;
        out.push(HalfPlane {
            point: u * bound,
            normal: -u,
        });
    }
    out
}

/// The robot's new velocity, eqs. (25)-(26): ORCA against the robots within
/// `params.neighbour_dist` (c = 1/2, horizon `time_horizon`) and every obstacle (c = 1,
/// horizon `obstacle_time_horizon`), inside the speed disc V_p and the acceleration polygon.
pub fn orca_velocity(
    me: &Disc,
    preferred: Vec2,
    robots: &[Disc],
    obstacles: &[Disc],
    params: &FormationParams,
) -> Selected {
    orca_velocity_squeezing(me, preferred, robots, obstacles, &[], params)
}

/// [`orca_velocity`] with `cell_only` static discs that keep no ORCA half-plane, only their
/// buffered-cell one (the step never overlaps them at the true radii, but the robot may pass
/// them closer than ORCA's margin: a robot boxed in by wrecks, behaviours/formation/
/// squeeze.rs). Without buffered cells they are ordinary obstacles.
pub fn orca_velocity_squeezing(
    me: &Disc,
    preferred: Vec2,
    robots: &[Disc],
    obstacles: &[Disc],
    cell_only: &[Disc],
    params: &FormationParams,
) -> Selected {
    let joined: Vec<Disc>;
    let (obstacles, cell_only) = if params.buffered_cells || cell_only.is_empty() {
        (obstacles, cell_only)
    } else {
        joined = obstacles.iter().chain(cell_only).copied().collect();
        (&joined[..], &[][..])
    };
    let within = |horizon: f64| {
        orca_velocity_within(me, preferred, robots, obstacles, cell_only, params, horizon)
    };
    let mut horizon = params.time_horizon;
    let mut selected = within(horizon);
    // Infeasible: the half-planes of a shorter horizon are wider (the truncated cone's cut-off
    // disc p / T grows), so they conflict less; one step is the least that still forbids an
    // overlap at the next step.
    while params.shrink_horizon_when_infeasible
        && selected.selection != Selection::Feasible
        && horizon > params.time_step
    {
        horizon = (0.5 * horizon).max(params.time_step);
        selected = within(horizon);
    }
    selected
}

/// [`orca_velocity`] with the robots' horizon `horizon`.
fn orca_velocity_within(
    me: &Disc,
    preferred: Vec2,
    robots: &[Disc],
    obstacles: &[Disc],
    cell_only: &[Disc],
    params: &FormationParams,
    horizon: f64,
) -> Selected {
    let tau = params.time_step;
    let keep = match params.max_accel {
        Some(a) => acceleration_polygon(me.velocity, a * tau, params.accel_polygon_sides),
        None => Vec::new(),
    };
    let mut hard: Vec<HalfPlane> = obstacles
        .iter()
        .map(|o| orca_half_plane(me, o, 1.0, params.obstacle_time_horizon, tau))
        .collect();
    hard.extend(wall_half_planes(me.position, params));
    if params.buffered_cells {
        let margin = (me.radius - params.robot_radius).max(0.0);
        let near: Vec<Disc> = robots
            .iter()
            .filter(|o| (o.position - me.position).norm() <= params.neighbour_dist)
            .copied()
            .collect();
        let statics: Vec<Disc>;
        let statics = if cell_only.is_empty() {
            obstacles
        } else {
            statics = obstacles.iter().chain(cell_only).copied().collect();
            &statics[..]
        };
        hard.extend(buffered_cell_half_planes(
            me, &near, statics, margin, params,
        ));
    }
    let soft: Vec<HalfPlane> = robots
        .iter()
        .filter(|o| (o.position - me.position).norm() <= params.neighbour_dist)
        .map(|o| orca_half_plane(me, o, 0.5, horizon, tau))
        .collect();
    select_velocity(&keep, &hard, &soft, params.max_speed, preferred)
}

#[cfg(test)]
mod tests;
