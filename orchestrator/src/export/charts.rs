//! An experiment's tables as SVG charts (`steps.svg`, `energy.svg` beside `results.md`): the
//! mean and the spread (min to max) against the swarm size, one line per mode, as the papers'
//! figures draw them. Axes, ticks and labels are drawn by hand (the SVG backend only, no font
//! engine: text is placed, never measured).

use plotters::prelude::*;
use std::path::Path;

/// Picture size in pixels.
const WIDTH: u32 = 760;
const HEIGHT: u32 = 480;
/// Plot area inset: left (y labels), right (legend), top (title), bottom (x labels).
const INSET: [i32; 4] = [70, 150, 40, 50];
/// Ticks on the y axis.
const Y_TICKS: usize = 5;
/// Horizontal offset between series at the same swarm size, in pixels.
const DODGE_PX: i32 = 8;

/// One point of a series: at swarm size `x`, the mean and the spread [lo, hi].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    pub x: f64,
    pub mean: f64,
    pub lo: f64,
    pub hi: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub label: String,
    pub points: Vec<Point>,
    /// Drawn dashed-looking (markers only, no spread): the paper's figures beside ours.
    pub reference: bool,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Chart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

/// Line colours, one per series in turn.
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// A round step for an axis spanning `span` in about `n` ticks (1, 2 or 5 x 10^k).
fn nice_step(span: f64, n: usize) -> f64 {
    let raw = (span / n as f64).max(f64::MIN_POSITIVE);
    let mag = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag)
}

/// Writes `chart` to `path`.
pub fn write(chart: &Chart, path: &Path) -> Result<(), String> {
    let e = |x: DrawingAreaErrorKind<std::io::Error>| format!("{}: {x:?}", path.display());
    let root = SVGBackend::new(path, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let pts = || chart.series.iter().flat_map(|s| s.points.iter());
    let (mut x0, mut x1) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut y1 = 0f64;
    for p in pts() {
        x0 = x0.min(p.x);
        x1 = x1.max(p.x);
        y1 = y1.max(p.hi).max(p.mean);
    }
    if !x0.is_finite() {
        (x0, x1) = (0.0, 1.0);
    }
    if x1 <= x0 {
        (x0, x1) = (x0 - 1.0, x1 + 1.0);
    }
    let pad = (x1 - x0) * 0.05;
    let (x0, x1) = (x0 - pad, x1 + pad);
    let step = nice_step(y1.max(1e-9), Y_TICKS);
    let y1 = (y1 / step).ceil().max(1.0) * step;
    let [l, r, t, b] = INSET;
    let (w, h) = (WIDTH as i32 - l - r, HEIGHT as i32 - t - b);
    let to = |x: f64, y: f64| -> (i32, i32) {
        (
            l + ((x - x0) / (x1 - x0) * w as f64).round() as i32,
            t + h - (y / y1 * h as f64).round() as i32,
        )
    };
    let font = ("sans-serif", 13).into_font().color(&BLACK);
    root.draw(&Text::new(chart.title.clone(), (l, 12), font.clone()))
        .map_err(e)?;
    root.draw(&Rectangle::new(
        [(l, t), (l + w, t + h)],
        BLACK.stroke_width(1),
    ))
    .map_err(e)?;
    // y ticks and grid.
    let mut y = 0.0;
    while y <= y1 + step * 1e-9 {
        let (_, py) = to(x0, y);
        root.draw(&PathElement::new(
            vec![(l, py), (l + w, py)],
            BLACK.mix(0.1).stroke_width(1),
        ))
        .map_err(e)?;
        root.draw(&Text::new(format!("{y}"), (l - 60, py - 7), font.clone()))
            .map_err(e)?;
        y += step;
    }
    // x ticks: the swarm sizes measured.
    let mut xs: Vec<f64> = pts().map(|p| p.x).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    for x in xs {
        let (px, _) = to(x, 0.0);
        root.draw(&PathElement::new(
            vec![(px, t + h), (px, t + h + 5)],
            BLACK.stroke_width(1),
        ))
        .map_err(e)?;
        root.draw(&Text::new(
            format!("{x}"),
            (px - 8, t + h + 8),
            font.clone(),
        ))
        .map_err(e)?;
    }
    root.draw(&Text::new(
        chart.x_label.clone(),
        (l + w / 2 - 40, t + h + 28),
        font.clone(),
    ))
    .map_err(e)?;
    root.draw(&Text::new(chart.y_label.clone(), (8, t - 22), font.clone()))
        .map_err(e)?;
    // Series at the same swarm size sit a few pixels apart (their spreads would cover each
    // other); a reference series takes the colour of the series before it (its mode's).
    let lines = chart.series.iter().filter(|s| !s.reference).count() as i32;
    let mut line_no = -1i32;
    for (k, s) in chart.series.iter().enumerate() {
        if !s.reference {
            line_no += 1;
        }
        let c = PALETTE[line_no.max(0) as usize % PALETTE.len()];
        let dodge = (2 * line_no.max(0) - (lines - 1)) * DODGE_PX / 2;
        let to = |x: f64, y: f64| {
            let (px, py) = to(x, y);
            (px + dodge, py)
        };
        let mut line: Vec<(i32, i32)> = s.points.iter().map(|p| to(p.x, p.mean)).collect();
        line.sort();
        if !s.reference {
            root.draw(&PathElement::new(line.clone(), c.stroke_width(2)))
                .map_err(e)?;
            for p in &s.points {
                // The spread: a bar from min to max with caps.
                let (px, lo) = to(p.x, p.lo);
                let (_, hi) = to(p.x, p.hi);
                for seg in [
                    vec![(px, lo), (px, hi)],
                    vec![(px - 4, lo), (px + 4, lo)],
                    vec![(px - 4, hi), (px + 4, hi)],
                ] {
                    root.draw(&PathElement::new(seg, c.stroke_width(1)))
                        .map_err(e)?;
                }
            }
        }
        for &m in &line {
            if s.reference {
                root.draw(&Cross::new(m, 4, c.stroke_width(2))).map_err(e)?;
            } else {
                root.draw(&Circle::new(m, 3, c.filled())).map_err(e)?;
            }
        }
        // The legend, right of the plot.
        let ly = t + 8 + 18 * k as i32;
        let lx = l + w + 12;
        if s.reference {
            root.draw(&Cross::new((lx + 10, ly + 7), 4, c.stroke_width(2)))
                .map_err(e)?;
        } else {
            root.draw(&PathElement::new(
                vec![(lx, ly + 7), (lx + 20, ly + 7)],
                c.stroke_width(2),
            ))
            .map_err(e)?;
        }
        root.draw(&Text::new(s.label.clone(), (lx + 26, ly), font.clone()))
            .map_err(e)?;
    }
    root.present().map_err(e)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chart_draws_one_line_a_spread_bar_per_point_and_a_legend_entry_per_series() {
        let p = |x: f64, mean: f64| Point {
            x,
            mean,
            lo: mean - 10.0,
            hi: mean + 10.0,
        };
        let chart = Chart {
            title: "steps".into(),
            x_label: "robots".into(),
            y_label: "steps".into(),
            series: vec![
                Series {
                    label: "BT".into(),
                    points: vec![p(20.0, 300.0), p(50.0, 200.0), p(100.0, 120.0)],
                    reference: false,
                },
                Series {
                    label: "BT (paper)".into(),
                    points: vec![p(20.0, 280.0)],
                    reference: true,
                },
            ],
        };
        let path = std::env::temp_dir().join(format!("chart-{}.svg", std::process::id()));
        write(&chart, &path).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        // plotters writes each text on a line of its own.
        let text = |t: &str| svg.contains(&format!("\n{t}\n</text>"));
        assert!(text("BT") && text("BT (paper)"), "{svg}");
        // Axis ticks: the swarm sizes, and y from 0 in round steps (max 310 -> 0..400 by 100).
        for label in ["20", "50", "100", "0", "300", "400"] {
            assert!(text(label), "{label} missing");
        }
        assert!(!text("500"));
        // One filled marker per mean of BT.
        assert_eq!(svg.matches("<circle").count(), 3);
    }

    #[test]
    fn axis_steps_are_round() {
        assert_eq!(nice_step(310.0, 5), 100.0);
        assert_eq!(nice_step(9.0, 5), 2.0);
        assert_eq!(nice_step(0.4, 5), 0.1);
        assert_eq!(nice_step(50.0, 5), 10.0);
    }
}
