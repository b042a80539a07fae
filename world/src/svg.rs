//! `run.svg`: arena, obstacles, start region, trajectories, start and end positions.

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

/// Trajectory colour of a display state: roaming blue, cooperative orange, declared green.
fn state_colour(state: u32) -> RGBColor {
    match state {
        swarm::frames::STATE_COOPERATIVE => RGBColor(230, 120, 0),
        swarm::frames::STATE_DECLARED => RGBColor(0, 150, 60),
        _ => RGBColor(60, 90, 200),
    }
}

/// Height of the legend strip under the arena, in pixels.
const LEGEND: u32 = 30;

/// The key under the arena: trajectory colours by state (search) and the markers.
fn legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    arena_height: u32,
    search: bool,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
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
    if search {
        line(root, state_colour(0), "roaming")?;
        line(
            root,
            state_colour(swarm::frames::STATE_COOPERATIVE),
            "cooperative",
        )?;
        line(
            root,
            state_colour(swarm::frames::STATE_DECLARED),
            "declared",
        )?;
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
    if search {
        marks.push(("target found", 3));
        marks.push(("target missed", 4));
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
            3 => root.draw(&Circle::new(c, 6, GREEN.filled()))?,
            _ => root.draw(&Circle::new(c, 6, RED.stroke_width(3)))?,
        }
        root.draw(&Text::new(label.to_string(), (x + 18, y), font.clone()))?;
        x += 26 + 7 * label.len() as i32;
    }
    Ok(())
}

pub fn write_svg(world: &World, path: &Path) -> Result<(), String> {
    let sc = &world.sc;
    let (w, h) = (sc.arena.width, sc.arena.height);
    let aspect = h / w;
    let height = (SIZE as f64 * aspect).round().max(100.0) as u32;
    let root = SVGBackend::new(path, (SIZE, height + LEGEND)).into_drawing_area();
    let e = |x: DrawingAreaErrorKind<std::io::Error>| format!("run.svg: {x:?}");
    root.fill(&WHITE).map_err(e)?;
    legend(&root, height, world.targets.is_some()).map_err(e)?;
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
    let n = world.n;
    let by_state = world.targets.is_some();
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
        // Search: each stretch coloured by the robot's state (as in the paper's Fig. 6).
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
                    state_colour(st).mix(0.7).stroke_width(1),
                ))
                .map_err(e)?;
        }
    }
    if let Some(t) = &world.targets {
        for (k, p) in t.pos.iter().enumerate() {
            let c = (p[0], p[1]);
            if t.found[k].is_some() {
                chart
                    .draw_series(std::iter::once(Circle::new(c, 7, GREEN.filled())))
                    .map_err(e)?;
                chart
                    .draw_series(std::iter::once(Circle::new(c, 7, BLACK.stroke_width(1))))
                    .map_err(e)?;
            } else {
                chart
                    .draw_series(std::iter::once(Circle::new(c, 7, RED.stroke_width(3))))
                    .map_err(e)?;
            }
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
    root.present().map_err(e)?;
    Ok(())
}
