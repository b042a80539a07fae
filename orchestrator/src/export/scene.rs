//! A tick as Foxglove's 3D panel draws it (`foxglove.SceneUpdate` in the world frame): the
//! arena's border, its obstacles, each robot as a disc with a heading arrow coloured by its
//! display state, and the mission's marks (targets, evaders, ranges, paths) labelled from its
//! legend. Every update first deletes all entities, then sends the tick's whole scene, so a
//! panel that seeks anywhere shows that tick and nothing older.

use super::foxglove::{
    ArrowPrimitive, Color, CylinderPrimitive, LinePrimitive, Pose, SceneEntity,
    SceneEntityDeletion, SceneUpdate, Time, TriangleListPrimitive, Vector3, DELETE_ALL, LINE_LOOP,
    LINE_STRIP,
};
use super::Run;
use swarm::layer::Mark;
use swarm::recording::TickRecord;

/// A mark's size in pixels (`px`) becomes arena units as in run.svg: the arena's longer side
/// is this many pixels.
const PICTURE_PX: f64 = 900.0;
/// A point robot (robot.radius = 0) is drawn with this radius, in pixels of that picture.
const POINT_ROBOT_PX: f64 = 4.0;
/// Thickness of the arena's, the obstacles' and the marks' lines, in pixels of that picture.
const LINE_PX: f64 = 1.5;
/// Height of the flat cylinders (robot discs, disc obstacles), as a fraction of their radius.
const DISC_HEIGHT: f64 = 0.2;
/// Points of a circle drawn as a line loop.
const CIRCLE_POINTS: usize = 48;
/// Opacity of a dead robot (alive ones are opaque).
const DEAD_ALPHA: f64 = 0.35;
/// Colour of a robot whose mission names no display states (and of the arena's lines).
const PLAIN: [u8; 3] = [60, 90, 200];
/// Obstacles' colour.
const OBSTACLE: [u8; 3] = [90, 90, 90];

/// The scale of a run's pictures: arena units per pixel of run.svg.
fn unit_per_px(run: &Run) -> f64 {
    run.meta.arena[0].max(run.meta.arena[1]) / PICTURE_PX
}

fn p3(p: [f64; 2]) -> Vector3 {
    Vector3 {
        x: p[0],
        y: p[1],
        z: 0.0,
    }
}

fn line(kind: u8, points: Vec<Vector3>, thickness: f64, color: Color) -> LinePrimitive {
    LinePrimitive {
        kind,
        pose: Pose::at(0.0, 0.0, 0.0, 0.0),
        thickness,
        scale_invariant: false,
        points,
        color,
        colors: Vec::new(),
        indices: Vec::new(),
    }
}

fn circle(at: [f64; 2], r: f64) -> Vec<Vector3> {
    (0..CIRCLE_POINTS)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / CIRCLE_POINTS as f64;
            p3([at[0] + r * a.cos(), at[1] + r * a.sin()])
        })
        .collect()
}

fn disc(at: [f64; 2], r: f64, color: Color) -> CylinderPrimitive {
    CylinderPrimitive {
        pose: Pose::at(at[0], at[1], r * DISC_HEIGHT / 2.0, 0.0),
        size: Vector3 {
            x: 2.0 * r,
            y: 2.0 * r,
            z: r * DISC_HEIGHT,
        },
        bottom_scale: 1.0,
        top_scale: 1.0,
        color,
    }
}

/// Whether two marks look alike (same kind and colours): how a mark finds its legend entry.
fn same_look(a: &Mark, b: &Mark) -> bool {
    match (a, b) {
        (
            Mark::Disc { fill, outline, .. },
            Mark::Disc {
                fill: f2,
                outline: o2,
                ..
            },
        ) => fill == f2 && outline == o2,
        (Mark::Ring { colour, .. }, Mark::Ring { colour: c2, .. })
        | (Mark::Circle { colour, .. }, Mark::Circle { colour: c2, .. })
        | (Mark::Path { colour, .. }, Mark::Path { colour: c2, .. }) => colour == c2,
        (Mark::Triangle { fill, .. }, Mark::Triangle { fill: f2, .. }) => fill == f2,
        _ => false,
    }
}

/// A mark of the mission's layer as an entity `mark/<k>`, with its legend label and kind.
fn mark_entity(run: &Run, time: Time, k: usize, m: &Mark) -> SceneEntity {
    let u = unit_per_px(run);
    let label = run
        .meta
        .legend
        .iter()
        .find(|l| same_look(&l.mark, m))
        .map_or("", |l| l.label);
    let kind = match m {
        Mark::Disc { .. } => "disc",
        Mark::Ring { .. } => "ring",
        Mark::Circle { .. } => "circle",
        Mark::Triangle { .. } => "triangle",
        Mark::Path { .. } => "path",
    };
    let mut e = SceneEntity::new(time, format!("mark/{k}"))
        .meta("kind", kind)
        .meta("label", label);
    match m {
        Mark::Disc {
            at,
            px,
            fill,
            outline,
        } => {
            let r = f64::from(*px) * u;
            e.cylinders.push(disc(*at, r, Color::rgb(*fill, 1.0)));
            if let Some(o) = outline {
                e.lines.push(line(
                    LINE_LOOP,
                    circle(*at, r),
                    LINE_PX * u,
                    Color::rgb(*o, 1.0),
                ));
            }
        }
        Mark::Ring {
            at,
            px,
            colour,
            width,
        } => e.lines.push(line(
            LINE_LOOP,
            circle(*at, f64::from(*px) * u),
            f64::from(*width) * u,
            Color::rgb(*colour, 1.0),
        )),
        Mark::Circle { at, radius, colour } => e.lines.push(line(
            LINE_LOOP,
            circle(*at, *radius),
            LINE_PX * u,
            Color::rgb(*colour, 1.0),
        )),
        Mark::Triangle {
            at,
            heading,
            px,
            fill,
        } => {
            // As the viewer draws it: the tip `px` ahead, the base corners behind.
            let l = f64::from(*px) * u;
            let corner = |a: f64, r: f64| {
                p3([
                    at[0] + r * (heading + a).cos(),
                    at[1] + r * (heading + a).sin(),
                ])
            };
            e.triangles.push(TriangleListPrimitive {
                pose: Pose::at(0.0, 0.0, 0.0, 0.0),
                points: vec![corner(0.0, l), corner(2.5, l * 0.6), corner(-2.5, l * 0.6)],
                color: Color::rgb(*fill, 1.0),
                colors: Vec::new(),
                indices: Vec::new(),
            });
        }
        Mark::Path { points, colour } => e.lines.push(line(
            LINE_STRIP,
            points.iter().map(|p| p3(*p)).collect(),
            LINE_PX * u,
            Color::rgb(*colour, 1.0),
        )),
    }
    e
}

/// The arena's border and obstacles: entities `arena`, `obstacle/<i>`, `disc/<i>`.
fn arena_entities(run: &Run, time: Time) -> Vec<SceneEntity> {
    let u = unit_per_px(run);
    let [w, h] = run.meta.arena;
    let grey = Color::rgb(OBSTACLE, 1.0);
    let mut out = Vec::new();
    let mut border = SceneEntity::new(time, "arena".into());
    border.lines.push(line(
        LINE_LOOP,
        vec![p3([0.0, 0.0]), p3([w, 0.0]), p3([w, h]), p3([0.0, h])],
        LINE_PX * u,
        Color::rgb(PLAIN, 1.0),
    ));
    out.push(border);
    for (i, o) in run.meta.obstacles.iter().enumerate() {
        let mut e = SceneEntity::new(time, format!("obstacle/{i}"));
        e.lines.push(line(
            LINE_LOOP,
            o.iter().map(|p| p3(*p)).collect(),
            2.0 * LINE_PX * u,
            grey,
        ));
        out.push(e);
    }
    for (i, (c, r)) in run.meta.discs.iter().enumerate() {
        let mut e = SceneEntity::new(time, format!("disc/{i}"));
        e.cylinders.push(disc(*c, *r, grey));
        out.push(e);
    }
    out
}

/// Robot `i` at tick `t`: a disc and a heading arrow, entity `robot/<i>`.
fn robot_entity(run: &Run, time: Time, t: &TickRecord, i: usize) -> SceneEntity {
    let u = unit_per_px(run);
    let [x, y, heading] = t.poses[i];
    let alive = t.alive.get(i).copied().unwrap_or(0) == 1;
    let state = t.states.get(i).copied().unwrap_or(0);
    let rgb = run
        .meta
        .states
        .iter()
        .find(|d| d.state == state)
        .map_or(PLAIN, |d| d.colour);
    let color = Color::rgb(rgb, if alive { 1.0 } else { DEAD_ALPHA });
    let r = if run.meta.robot_radius > 0.0 {
        run.meta.robot_radius
    } else {
        POINT_ROBOT_PX * u
    };
    let mut e = SceneEntity::new(time, format!("robot/{i}"))
        .meta("robot", i)
        .meta("state", state)
        .meta("state_name", run.state_name(state))
        .meta("alive", alive);
    e.cylinders.push(disc([x, y], r, color));
    let z = r * DISC_HEIGHT;
    e.arrows.push(ArrowPrimitive {
        pose: Pose::at(x, y, z, heading),
        shaft_length: 1.5 * r,
        shaft_diameter: 0.3 * r,
        head_length: 0.8 * r,
        head_diameter: 0.8 * r,
        color: Color::rgb([0, 0, 0], color.a),
    });
    e
}

/// The scene of tick `t` at simulated time `ns`.
pub fn update(run: &Run, t: &TickRecord, ns: u64) -> SceneUpdate {
    let time = Time::from_ns(ns);
    let mut entities = arena_entities(run, time);
    entities.extend((0..t.poses.len()).map(|i| robot_entity(run, time, t, i)));
    if let Some(marks) = &t.layer {
        entities.extend(
            marks
                .iter()
                .enumerate()
                .map(|(k, m)| mark_entity(run, time, k, m)),
        );
    }
    SceneUpdate {
        deletions: vec![SceneEntityDeletion {
            timestamp: time,
            kind: DELETE_ALL,
            id: String::new(),
        }],
        entities,
    }
}
