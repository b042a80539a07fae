//! Every chart an experiment draws (`steps.svg`, `energy.svg`, the formation's Fig. 9, the
//! hunt's reward iterations, the CBCA utility curves and Figs. 4.6-4.7): lines against x, with
//! the spread (min to max) where a point has one, the papers' values as crosses, a title,
//! numbered axes with ticks, and a legend beside the plot. Axes, ticks and labels are drawn by
//! hand (the SVG backend only, no font engine: text is placed, never measured).

use plotters::prelude::*;
use std::path::Path;

/// The plot area's width and the picture's height, in pixels; the picture is as wide as the
/// plot, its y labels and its legend.
const PLOT_WIDTH: i32 = 540;
const HEIGHT: u32 = 480;
/// Plot area inset: left (y labels), top (title), bottom (x labels).
const INSET: [i32; 3] = [70, 50, 50];
/// The legend's width: its line sample and gaps, plus this many pixels a character of the
/// longest label (13 px sans-serif averages under 8), within [LEGEND_MIN, LEGEND_MAX].
const LEGEND_PX_PER_CHAR: i32 = 8;
const LEGEND_MIN: i32 = 110;
const LEGEND_MAX: i32 = 360;
/// Ticks on the y axis.
const Y_TICKS: usize = 5;
/// Horizontal offset between series at the same swarm size, in pixels.
const DODGE_PX: i32 = 8;
/// Up to this many distinct x values, the ticks sit at them (swarm sizes) and series are
/// dodged; beyond, the x axis gets round ticks (rounds, ticks, time) and no dodge.
const X_AT_VALUES_MAX: usize = 12;
/// Ticks on an x axis of round ticks.
const X_TICKS: usize = 8;
/// A series with more points than this is drawn as a line only (no marker a point).
const MARKERS_MAX: usize = 30;

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

/// Line colours, one per series in turn: the 20 of matplotlib's "tab20" (dark, then light of
/// each hue), so a chart of up to 20 lines (a robot each) has no two alike.
const PALETTE: [RGBColor; 20] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(174, 199, 232),
    RGBColor(255, 152, 150),
    RGBColor(152, 223, 138),
    RGBColor(255, 187, 120),
    RGBColor(197, 176, 213),
    RGBColor(196, 156, 148),
    RGBColor(247, 182, 210),
    RGBColor(158, 218, 229),
    RGBColor(199, 199, 199),
    RGBColor(219, 219, 141),
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

/// A tick's label: as many decimals as the step needs, no float noise (0.30000000000000004).
fn tick_label(v: f64, step: f64) -> String {
    let digits = (-step.log10().floor()).max(0.0) as usize;
    let v = if v.abs() < step * 1e-9 { 0.0 } else { v };
    format!("{v:.digits$}")
}

/// Writes `chart` to `path`.
pub fn write(chart: &Chart, path: &Path) -> Result<(), String> {
    let e = |x: DrawingAreaErrorKind<std::io::Error>| format!("{}: {x:?}", path.display());
    let longest = chart
        .series
        .iter()
        .map(|s| s.label.chars().count())
        .max()
        .unwrap_or(0) as i32;
    let r = (50 + LEGEND_PX_PER_CHAR * longest).clamp(LEGEND_MIN, LEGEND_MAX);
    let [l, t, b] = INSET;
    let width = (l + PLOT_WIDTH + r) as u32;
    let root = SVGBackend::new(path, (width, HEIGHT)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let pts = || {
        chart
            .series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|p| p.x.is_finite() && p.mean.is_finite())
    };
    let (mut x0, mut x1) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut y0, mut y1) = (0f64, 0f64);
    for p in pts() {
        x0 = x0.min(p.x);
        x1 = x1.max(p.x);
        y0 = y0.min(p.lo.min(p.mean));
        y1 = y1.max(p.hi.max(p.mean));
    }
    if !x0.is_finite() {
        (x0, x1) = (0.0, 1.0);
    }
    if x1 <= x0 {
        (x0, x1) = (x0 - 1.0, x1 + 1.0);
    }
    let mut xs: Vec<f64> = pts().map(|p| p.x).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let at_values = xs.len() <= X_AT_VALUES_MAX;
    let (x0, x1) = if at_values {
        let pad = (x1 - x0) * 0.05;
        (x0 - pad, x1 + pad)
    } else {
        (x0, x1)
    };
    let step = nice_step((y1 - y0).max(1e-9), Y_TICKS);
    let y0 = (y0 / step).floor() * step;
    let y1 = ((y1 / step).ceil() * step).max(y0 + step);
    let (w, h) = (PLOT_WIDTH, HEIGHT as i32 - t - b);
    let to = |x: f64, y: f64| -> (i32, i32) {
        (
            l + ((x - x0) / (x1 - x0) * w as f64).round() as i32,
            t + h - ((y - y0) / (y1 - y0) * h as f64).round() as i32,
        )
    };
    let font = ("sans-serif", 13).into_font().color(&BLACK);
    root.draw(&Text::new(chart.title.clone(), (l, 6), font.clone()))
        .map_err(e)?;
    root.draw(&Rectangle::new(
        [(l, t), (l + w, t + h)],
        BLACK.stroke_width(1),
    ))
    .map_err(e)?;
    // y ticks and grid.
    let mut k = 0;
    loop {
        let y = y0 + step * k as f64;
        if y > y1 + step * 1e-9 {
            break;
        }
        let (_, py) = to(x0, y);
        root.draw(&PathElement::new(
            vec![(l, py), (l + w, py)],
            BLACK.mix(0.1).stroke_width(1),
        ))
        .map_err(e)?;
        root.draw(&Text::new(
            tick_label(y, step),
            (l - 60, py - 7),
            font.clone(),
        ))
        .map_err(e)?;
        k += 1;
    }
    // x ticks: the x values measured (swarm sizes), or round steps over a long axis.
    let ticks: Vec<(f64, String)> = if at_values {
        xs.iter().map(|&x| (x, format!("{x}"))).collect()
    } else {
        let xstep = nice_step(x1 - x0, X_TICKS);
        let first = (x0 / xstep).ceil() as i64;
        let last = (x1 / xstep).floor() as i64;
        (first..=last)
            .map(|i| {
                let x = i as f64 * xstep;
                (x, tick_label(x, xstep))
            })
            .collect()
    };
    for (x, label) in ticks {
        let (px, _) = to(x, y0);
        root.draw(&PathElement::new(
            vec![(px, t + h), (px, t + h + 5)],
            BLACK.stroke_width(1),
        ))
        .map_err(e)?;
        root.draw(&Text::new(label, (px - 8, t + h + 8), font.clone()))
            .map_err(e)?;
    }
    root.draw(&Text::new(
        chart.x_label.clone(),
        (l + w / 2 - 40, t + h + 28),
        font.clone(),
    ))
    .map_err(e)?;
    root.draw(&Text::new(chart.y_label.clone(), (8, t - 20), font.clone()))
        .map_err(e)?;
    // Series at the same swarm size sit a few pixels apart when they have spreads (which
    // would cover each other); a reference series takes the colour of the series before it
    // (its mode's).
    let lines = chart.series.iter().filter(|s| !s.reference).count() as i32;
    let spreads = pts().any(|p| p.hi > p.lo);
    let mut line_no = -1i32;
    for (k, s) in chart.series.iter().enumerate() {
        if !s.reference {
            line_no += 1;
        }
        let c = PALETTE[line_no.max(0) as usize % PALETTE.len()];
        let dodge = if at_values && spreads {
            (2 * line_no.max(0) - (lines - 1)) * DODGE_PX / 2
        } else {
            0
        };
        let to = |x: f64, y: f64| {
            let (px, py) = to(x, y);
            (px + dodge, py)
        };
        let points: Vec<&Point> = s
            .points
            .iter()
            .filter(|p| p.x.is_finite() && p.mean.is_finite())
            .collect();
        let mut line: Vec<(i32, i32)> = points.iter().map(|p| to(p.x, p.mean)).collect();
        line.sort();
        if !s.reference {
            root.draw(&PathElement::new(line.clone(), c.stroke_width(2)))
                .map_err(e)?;
            for p in points.iter().filter(|p| p.hi > p.lo) {
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
        if line.len() <= MARKERS_MAX || s.reference {
            for &m in &line {
                if s.reference {
                    root.draw(&Cross::new(m, 4, c.stroke_width(2))).map_err(e)?;
                } else {
                    root.draw(&Circle::new(m, 3, c.filled())).map_err(e)?;
                }
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

    /// A long x axis (rounds, ticks) gets round ticks, not one a value; a negative y gets
    /// its own ticks below 0 (-70 .. 50 in steps of 50: -100 .. 50); a line of many points has
    /// no marker a point.
    #[test]
    fn a_long_series_gets_round_x_ticks_and_a_negative_axis() {
        let chart = Chart {
            title: "utility".into(),
            x_label: "time".into(),
            y_label: "utility".into(),
            series: vec![Series {
                label: "R1".into(),
                points: (0..=120)
                    .map(|k| {
                        let y = 50.0 - k as f64;
                        Point {
                            x: k as f64 * 0.1,
                            mean: y,
                            lo: y,
                            hi: y,
                        }
                    })
                    .collect(),
                reference: false,
            }],
        };
        let path = std::env::temp_dir().join(format!("chart-long-{}.svg", std::process::id()));
        write(&chart, &path).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        let text = |t: &str| svg.contains(&format!("\n{t}\n</text>"));
        for label in ["0", "2", "12", "-100", "-50", "50", "R1"] {
            assert!(text(label), "{label} missing");
        }
        assert!(!text("0.1") && !text("1.1"), "one tick a value");
        assert_eq!(svg.matches("<circle").count(), 0);
        assert_eq!(tick_label(0.30000000000000004, 0.1), "0.3");
    }

    #[test]
    fn axis_steps_are_round() {
        assert_eq!(nice_step(310.0, 5), 100.0);
        assert_eq!(nice_step(9.0, 5), 2.0);
        assert_eq!(nice_step(0.4, 5), 0.1);
        assert_eq!(nice_step(50.0, 5), 10.0);
    }
}
