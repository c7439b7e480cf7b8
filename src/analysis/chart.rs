//! Charts of error against time and against samples (plotters), as PNG and SVG. Text is drawn
//! with a bundled font (DejaVu Sans, `assets/fonts/`), so no system font library is needed.

use crate::analysis::curve::Point;
use crate::film::output::{write_rgb8_png, write_text};
use anyhow::{anyhow, Result};
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use std::path::Path;

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
const SIZE: (u32, u32) = (900, 600);
/// Distinguishable line colours (Okabe and Ito's colour-blind-safe set).
const PALETTE: [RGBColor; 10] = [
    RGBColor(213, 94, 0),
    RGBColor(0, 114, 178),
    RGBColor(0, 158, 115),
    RGBColor(230, 159, 0),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(136, 34, 85),
    RGBColor(153, 153, 51),
    RGBColor(120, 120, 120),
];

/// How a series is drawn: its colour names its method (the last word of its name: "path",
/// "vcm", ...), its line and marker the renderer and backend before it ("hexray cpu", "hexray
/// gpu", "mitsuba"), so that one method's curves share a colour across backends and renderers
/// and no two of up to thirty series look alike.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Look {
    /// Index into [`PALETTE`].
    color: usize,
    /// 0: a solid line with dots; 1: dashes with triangles; 2: short dashes with crosses.
    style: usize,
}

/// The number of line styles of [`Look::style`].
const STYLES: usize = 3;
/// Each style's dash and gap in pixels (style 0's line is solid).
const DASHES: [(u32, u32); STYLES] = [(20, 0), (10, 6), (3, 4)];

/// Each series' look, from the names in order: colours by the methods' order of first
/// appearance, styles by the prefixes'. Where two series would still share a look (more than
/// [`PALETTE`]'s methods, or names not of that form), the later one takes the next look that
/// no series has yet.
fn looks(names: &[&str]) -> Vec<Look> {
    // The index of `key` among the keys seen so far, in order of first appearance.
    fn index<'a>(seen: &mut Vec<&'a str>, key: &'a str) -> usize {
        seen.iter().position(|&k| k == key).unwrap_or_else(|| {
            seen.push(key);
            seen.len() - 1
        })
    }
    let (mut methods, mut groups) = (Vec::new(), Vec::new());
    let mut taken: Vec<Look> = Vec::new();
    for name in names {
        let (group, method) = name.rsplit_once(' ').unwrap_or(("", name));
        let (m, g) = (index(&mut methods, method), index(&mut groups, group));
        let mut look = Look {
            color: m % PALETTE.len(),
            style: g % STYLES,
        };
        let all = PALETTE.len() * STYLES;
        let mut k = look.style * PALETTE.len() + look.color;
        for _ in 0..all {
            if !taken.contains(&look) {
                break;
            }
            k = (k + 1) % all;
            look = Look {
                color: k % PALETTE.len(),
                style: k / PALETTE.len(),
            };
        }
        taken.push(look);
    }
    taken
}

fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // The bytes are a valid TrueType font, checked by `curve_relmse_falls_with_spp_and_its_charts_decode` (tests/curve.rs).
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Which quantity goes on the x axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum XAxis {
    Seconds,
    Spp,
}

/// Draws relMSE against seconds or spp, log-log, one line per series (in order of first
/// appearance), with `caption` under the title; writes `stem.png` and `stem.svg`.
pub fn relmse_chart(
    points: &[Point],
    x: XAxis,
    title: &str,
    caption: &str,
    stem: &Path,
) -> Result<()> {
    register_font();
    let mut series: Vec<Series> = Vec::new();
    for p in points {
        let xv = match x {
            XAxis::Seconds => p.seconds,
            XAxis::Spp => p.spp as f64,
        };
        if !(xv > 0.0 && p.relmse > 0.0) {
            continue;
        }
        match series.iter_mut().find(|(n, _)| *n == p.backend) {
            Some((_, v)) => v.push((xv, p.relmse)),
            None => series.push((p.backend.clone(), vec![(xv, p.relmse)])),
        }
    }
    let all = series.iter().flat_map(|(_, v)| v.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(a, b) in all {
        (x0, x1, y0, y1) = (x0.min(a), x1.max(a), y0.min(b), y1.max(b));
    }
    if x0 > x1 {
        return Err(anyhow!(
            "nothing to chart: no point with positive x and relMSE"
        ));
    }
    let (x0, x1, y0, y1) = (x0 / 1.5, x1 * 1.5, y0 / 1.5, y1 * 1.5);
    let x_label = match x {
        XAxis::Seconds => "render time (s, after warm-up)",
        XAxis::Spp => "samples per pixel",
    };

    let bounds = (x0, x1, y0, y1);
    let mut pixels = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    draw(
        BitMapBackend::with_buffer(&mut pixels, SIZE).into_drawing_area(),
        &series,
        bounds,
        title,
        caption,
        x_label,
    )?;
    write_rgb8_png(&stem.with_extension("png"), SIZE.0, SIZE.1, &pixels)?;
    let mut svg = String::new();
    draw(
        SVGBackend::with_string(&mut svg, SIZE).into_drawing_area(),
        &series,
        bounds,
        title,
        caption,
        x_label,
    )?;
    write_text(&stem.with_extension("svg"), &svg)?;
    Ok(())
}

type Series = (String, Vec<(f64, f64)>);

#[allow(clippy::too_many_arguments)]
fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    series: &[Series],
    (x0, x1, y0, y1): (f64, f64, f64, f64),
    title: &str,
    caption: &str,
    x_label: &str,
) -> Result<()> {
    root.fill(&WHITE).map_err(|e| anyhow!("{e:?}"))?;
    let (top, rest) = root.split_vertically(64);
    top.draw(&Text::new(
        title.to_string(),
        (20, 8),
        ("sans-serif", 22).into_font(),
    ))
    .map_err(|e| anyhow!("{e:?}"))?;
    top.draw(&Text::new(
        caption.to_string(),
        (20, 38),
        ("sans-serif", 14).into_font().color(&RGBColor(80, 80, 80)),
    ))
    .map_err(|e| anyhow!("{e:?}"))?;
    let mut chart = ChartBuilder::on(&rest)
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(|e| anyhow!("{e:?}"))?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc("relMSE")
        .label_style(("sans-serif", 14))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .x_label_formatter(&|v| {
            if *v >= 1.0 {
                format!("{v:.0}")
            } else {
                format!("{v:.2}")
            }
        })
        .draw()
        .map_err(|e| anyhow!("{e:?}"))?;
    let names: Vec<&str> = series.iter().map(|(n, _)| n.as_str()).collect();
    for ((name, pts), look) in series.iter().zip(looks(&names)) {
        let color = PALETTE[look.color].to_rgba();
        let line = color.stroke_width(2);
        let pts = pts.iter().copied();
        let (dash, gap) = DASHES[look.style];
        let drawn = match look.style {
            0 => chart.draw_series(LineSeries::new(pts.clone(), line)),
            _ => chart.draw_series(DashedLineSeries::new(pts.clone(), dash, gap, line)),
        }
        .map_err(|e| anyhow!("{e:?}"))?;
        drawn.label(name.clone()).legend(move |(x, y)| {
            DashedPathElement::new(vec![(x, y), (x + 20, y)], dash, gap, line)
        });
        match look.style {
            0 => chart.draw_series(pts.map(|p| Circle::new(p, 3, color.filled()))),
            1 => chart.draw_series(pts.map(|p| TriangleMarker::new(p, 4, color.filled()))),
            _ => chart.draw_series(pts.map(|p| Cross::new(p, 4, line))),
        }
        .map_err(|e| anyhow!("{e:?}"))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 14))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| anyhow!("{e:?}"))?;
    root.present().map_err(|e| anyhow!("{e:?}"))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fourteen series of docs/methods.md's charts: each method keeps its colour across
    /// the backends and Mitsuba, each renderer-backend its line, and no two series look alike.
    #[test]
    fn each_method_has_one_colour_and_no_two_series_look_alike() {
        let mut names = Vec::new();
        for group in ["hexray cpu", "hexray gpu"] {
            for method in ["path", "light", "bdpt", "sppm", "vcm", "vcm-full"] {
                names.push(format!("{group} {method}"));
            }
        }
        names.extend(["mitsuba path".to_string(), "mitsuba ptracer".to_string()]);
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        let got = looks(&names);
        for (i, a) in got.iter().enumerate() {
            for (j, b) in got.iter().enumerate().skip(i + 1) {
                assert_ne!(a, b, "{} and {} look alike", names[i], names[j]);
            }
        }
        assert_eq!(got[0].color, got[6].color, "path on both backends");
        assert_eq!(got[0].color, got[12].color, "path in both renderers");
        assert_ne!(got[0].style, got[6].style);
        assert_ne!(got[6].style, got[12].style);
    }

    /// Thirty series of one prefix, three times the palette's colours, all look different.
    #[test]
    fn series_beyond_the_palette_take_looks_not_yet_taken() {
        let names: Vec<String> = (0..30).map(|i| format!("hexray m{i}")).collect();
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        let got = looks(&names);
        for (i, a) in got.iter().enumerate() {
            assert!(!got[..i].contains(a), "series {i} repeats a look");
        }
    }
}
