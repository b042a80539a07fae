//! `run.svg`: arena, obstacles, start region, trajectories, start and end positions.

use crate::mission::{DisplayState, Mark};
use crate::world::World;
use plotters::prelude::*;
use std::path::Path;

/// Picture size in pixels (square arena maps to a square picture).
const SIZE: u32 = 900;

fn robot_colour(i: usize, n: usize) -> RGBColor {
    let h = i as f64 / n.max(1) as f64;
    let HSLColor(h, s, l) = HSLColor(h, 0.65, 0.45);
    // HSL -> RGB
    let c = (1.0 - (2.0 * l - 1.0).abs()) * s;
    let hp = h * 6.0;
    let x = c * (1.0 - (hp % 2.0 - 1.0).abs());
    let (r, g, b) = match hp as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = l - c / 2.0;
    RGBColor(
        ((r + m) * 255.0) as u8,
        ((g + m) * 255.0) as u8,
        ((b + m) * 255.0) as u8,
    )
}

/// Trajectory colour of a display state, as the mission names it (the first state's colour
/// for a state it does not name).
fn state_colour(states: &[DisplayState], state: u32) -> RGBColor {
    let c = states
        .iter()
        .find(|d| d.state as u32 == state)
        .or(states.first())
        .map_or([60, 90, 200], |d| d.colour);
    rgb(c)
}

fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

/// Draws one mark of a mission's layer at pixel `c` (`to_px` maps arena units to pixels, for
/// the marks sized in arena units).
fn draw_mark<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    mark: &Mark,
    c: (i32, i32),
    to_px: f64,
    path: &[(i32, i32)],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    match mark {
        Mark::Disc {
            px, fill, outline, ..
        } => {
            root.draw(&Circle::new(c, *px, rgb(*fill).filled()))?;
            if let Some(o) = outline {
                root.draw(&Circle::new(c, *px, rgb(*o).stroke_width(1)))?;
            }
        }
        Mark::Ring {
            px, colour, width, ..
        } => root.draw(&Circle::new(c, *px, rgb(*colour).stroke_width(*width)))?,
        Mark::Circle { radius, colour, .. } => root.draw(&Circle::new(
            c,
            (radius * to_px).round().max(1.0) as u32,
            rgb(*colour).stroke_width(1),
        ))?,
        Mark::Triangle {
            heading, px, fill, ..
        } => {
            // Screen y grows downwards: the arena heading turns the other way.
            let l = *px as f64;
            let pt = |a: f64, r: f64| {
                (
                    c.0 + (r * a.cos()).round() as i32,
                    c.1 - (r * a.sin()).round() as i32,
                )
            };
            let tri = vec![
                pt(*heading, l * 0.6),
                pt(heading + 2.5, l * 0.45),
                pt(heading - 2.5, l * 0.45),
            ];
            root.draw(&Polygon::new(tri.clone(), rgb(*fill).filled()))?;
            let mut outline = tri.clone();
            outline.push(tri[0]);
            root.draw(&PathElement::new(outline, BLACK.stroke_width(1)))?;
        }
        Mark::Path { colour, .. } => root.draw(&PathElement::new(
            path.to_vec(),
            rgb(*colour).stroke_width(2),
        ))?,
    }
    Ok(())
}

/// Height of the legend strip under the arena, in pixels.
const LEGEND: u32 = 30;

/// The key under the arena: trajectory colours by state (search) and the markers.
fn legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    arena_height: u32,
    world: &World,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let states = world.mission.display_states();
    let y = arena_height as i32 + 8;
    let font = ("sans-serif", 13).into_font().color(&BLACK);
    let mut x = 12;
    let mut line = |root: &DrawingArea<DB, _>, col: RGBColor, label: &str| {
        let r = root.draw(&PathElement::new(
            vec![(x, y + 7), (x + 22, y + 7)],
            col.stroke_width(3),
        ));
        let t = root.draw(&Text::new(label.to_string(), (x + 28, y), font.clone()));
        x += 36 + 7 * label.len() as i32;
        r.and(t)
    };
    if !states.is_empty() {
        for d in states {
            line(root, rgb(d.colour), d.name)?;
        }
    } else {
        line(
            root,
            robot_colour(0, 3),
            "trajectory (one colour per robot)",
        )?;
    }
    let mut marks: Vec<(&str, i32)> = vec![
        ("start region", 0),
        ("final position", 1),
        ("dead robot", 2),
    ];
    let mission_marks = world.mission.legend();
    for (k, e) in mission_marks.iter().enumerate() {
        marks.push((e.label, 3 + k as i32));
    }
    for (label, kind) in marks {
        let c = (x + 6, y + 7);
        match kind {
            0 => root.draw(&Rectangle::new(
                [(x, y + 1), (x + 12, y + 13)],
                RGBColor(80, 80, 200).stroke_width(1),
            ))?,
            1 => root.draw(&Circle::new(c, 4, robot_colour(0, 3).filled()))?,
            2 => root.draw(&Cross::new(c, 5, BLACK.stroke_width(2)))?,
            k => draw_mark(root, &mission_marks[(k - 3) as usize].mark, c, 1.0, &[c])?,
        }
        root.draw(&Text::new(label.to_string(), (x + 18, y), font.clone()))?;
        x += 26 + 7 * label.len() as i32;
    }
    Ok(())
}

/// The run's picture as SVG text (written whole by the caller: `output::write_atomic`).
pub fn svg_text(world: &World) -> Result<String, String> {
    let mut text = String::new();
    draw_svg(world, &mut text)?;
    Ok(text)
}

/// Writes the run's picture to `path` whole or not at all; errors name the file.
pub fn write_svg(world: &World, path: &Path) -> Result<(), String> {
    crate::output::write_atomic(path, svg_text(world)?.as_bytes()).map_err(|e| e.to_string())
}

fn draw_svg(world: &World, out: &mut String) -> Result<(), String> {
    let sc = &world.sc;
    let (w, h) = (sc.arena.width, sc.arena.height);
    let aspect = h / w;
    let height = (SIZE as f64 * aspect).round().max(100.0) as u32;
    let root = SVGBackend::with_string(out, (SIZE, height + LEGEND)).into_drawing_area();
    let e = |x: DrawingAreaErrorKind<std::io::Error>| format!("run.svg: {x:?}");
    root.fill(&WHITE).map_err(e)?;
    legend(&root, height, world).map_err(e)?;
    let area = root.margin(10, 10 + LEGEND, 10, 10);
    // Arena coordinates with y up.
    let mut chart = ChartBuilder::on(&area)
        .build_cartesian_2d(0f64..w, 0f64..h)
        .map_err(e)?;
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [(0.0, 0.0), (w, h)],
            BLACK.stroke_width(2),
        )))
        .map_err(e)?;
    let [x0, y0, x1, y1] = sc.arena.start_region;
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [(x0, y0), (x1, y1)],
            RGBColor(120, 120, 255).mix(0.15).filled(),
        )))
        .map_err(e)?;
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [(x0, y0), (x1, y1)],
            RGBColor(80, 80, 200).stroke_width(1),
        )))
        .map_err(e)?;
    for o in &sc.arena.obstacles {
        let pts: Vec<(f64, f64)> = o.points.iter().map(|p| (p[0], p[1])).collect();
        chart
            .draw_series(std::iter::once(Polygon::new(pts, BLACK.mix(0.85).filled())))
            .map_err(e)?;
    }
    for d in &sc.arena.discs {
        let pts: Vec<(f64, f64)> = d.outline(96).iter().map(|p| (p[0], p[1])).collect();
        chart
            .draw_series(std::iter::once(Polygon::new(pts, BLACK.mix(0.85).filled())))
            .map_err(e)?;
    }
    let n = world.n;
    let states = world.mission.display_states();
    let by_state = !states.is_empty();
    for (i, traj) in world.trajectories.iter().enumerate() {
        if !by_state {
            let col = robot_colour(i, n);
            let mut pts: Vec<(f64, f64)> = traj.iter().map(|p| (p[0], p[1])).collect();
            pts.push((world.poses[i][0], world.poses[i][1]));
            chart
                .draw_series(LineSeries::new(pts, col.mix(0.6).stroke_width(1)))
                .map_err(e)?;
            continue;
        }
        // Each stretch coloured by the robot's display state (search: as the paper's Fig. 6).
        let mut j = 0;
        while j + 1 < traj.len() {
            let st = traj[j + 1][2] as u32;
            let mut pts = vec![(traj[j][0], traj[j][1])];
            while j + 1 < traj.len() && traj[j + 1][2] as u32 == st {
                j += 1;
                pts.push((traj[j][0], traj[j][1]));
            }
            chart
                .draw_series(LineSeries::new(
                    pts,
                    state_colour(states, st).mix(0.7).stroke_width(1),
                ))
                .map_err(e)?;
        }
    }
    for (i, s) in world.start.iter().enumerate() {
        let col = robot_colour(i, n);
        chart
            .draw_series(std::iter::once(Circle::new((s[0], s[1]), 2, col.filled())))
            .map_err(e)?;
    }
    for i in 0..n {
        let col = robot_colour(i, n);
        let p = (world.poses[i][0], world.poses[i][1]);
        if world.alive[i] {
            chart
                .draw_series(std::iter::once(Circle::new(p, 4, col.filled())))
                .map_err(e)?;
        } else {
            // A dead robot: a black cross.
            chart
                .draw_series(std::iter::once(Cross::new(p, 5, BLACK.stroke_width(2))))
                .map_err(e)?;
        }
    }
    // The mission's layer last, in pixels of the chart's area: its marks (hunt's robot
    // triangles, search's targets) lie over the start and end dots, not under them.
    let to_px = (SIZE as f64 - 20.0) / w;
    for mark in world.mission.layer() {
        let (at, pts) = match &mark {
            Mark::Disc { at, .. }
            | Mark::Ring { at, .. }
            | Mark::Circle { at, .. }
            | Mark::Triangle { at, .. } => (*at, vec![]),
            Mark::Path { points, .. } => {
                (points.first().copied().unwrap_or([0.0; 2]), points.clone())
            }
        };
        let c = chart.backend_coord(&(at[0], at[1]));
        let path: Vec<(i32, i32)> = pts
            .iter()
            .map(|p| chart.backend_coord(&(p[0], p[1])))
            .collect();
        draw_mark(&root, &mark, c, to_px, &path).map_err(e)?;
    }
    root.present().map_err(e)?;
    Ok(())
}
