//! The report's figures as SVG files for papers: each [`Figure`] drawn as the page draws
//! it (same data, colours, dashes, markers and legend), sized in points with text of 11 pt
//! and more at natural size, every label XML-escaped. Each dataset is one
//! `<g class="series">`; legend texts carry `class="legend"`.

use super::escape;
use super::figures::{Dataset, Figure, FigureKind, LegendEntry, ReportFigures, Swatch};
use super::style::{DASHES, MARKERS};
use std::fmt::Write;

/// Width of every figure, pt.
const WIDTH: f64 = 460.0;
const FONT: &str = "Helvetica, Arial, sans-serif";
const INK: &str = "#1d2330";
const GRID: &str = "#d9dde5";
/// Font sizes, pt.
const TITLE_PT: f64 = 13.0;
const LABEL_PT: f64 = 12.0;
const TICK_PT: f64 = 11.0;
const LEGEND_PT: f64 = 11.0;
const LEGEND_ROW: f64 = 17.0;

/// One SVG file of a report: `<id>.svg`.
#[derive(Debug, Clone, PartialEq)]
pub struct SvgFigure {
    /// The figure's id: its canvas in the page and its file stem.
    pub id: String,
    /// The SVG document.
    pub svg: String,
}

impl SvgFigure {
    /// `<id>.svg`.
    pub fn file_name(&self) -> String {
        format!("{}.svg", self.id)
    }
}

/// Every figure of a report as SVG, in page order.
pub fn svg_figures(figures: &ReportFigures) -> Vec<SvgFigure> {
    figures
        .all()
        .map(|f| SvgFigure {
            id: f.id.clone(),
            svg: figure_svg(f),
        })
        .collect()
}

/// A number as SVG writes it: two decimals at most.
fn n(v: f64) -> String {
    let s = format!("{v:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

/// Estimated width of `text` at `size` pt (Helvetica averages about 0.55 em).
fn text_width(text: &str, size: f64) -> f64 {
    text.chars().count() as f64 * size * 0.55
}

fn text(out: &mut String, x: f64, y: f64, size: f64, anchor: &str, extra: &str, s: &str) {
    if s.is_empty() {
        return;
    }
    let _ = write!(
        out,
        r#"<text x="{}" y="{}" font-size="{}" text-anchor="{anchor}" fill="{INK}"{extra}>{}</text>"#,
        n(x),
        n(y),
        n(size),
        escape(s)
    );
}

fn dash_attr(dash: usize) -> String {
    let d = DASHES[dash % DASHES.len()];
    if d.is_empty() {
        String::new()
    } else {
        format!(
            r#" stroke-dasharray="{}""#,
            d.iter().map(|v| n(*v)).collect::<Vec<_>>().join(" ")
        )
    }
}

/// A marker of shape `MARKERS[marker]` centred on (x, y), radius r.
fn marker(out: &mut String, marker: usize, x: f64, y: f64, r: f64, color: &str, alpha: f64) {
    let paint = format!(
        r#"fill="{color}" fill-opacity="{}" stroke="{color}" stroke-width="1""#,
        n(alpha)
    );
    let poly = |pts: &[(f64, f64)]| {
        pts.iter()
            .map(|(a, b)| format!("{},{}", n(x + a * r), n(y + b * r)))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let _ = match MARKERS[marker % MARKERS.len()] {
        "triangle" => write!(
            out,
            r#"<polygon points="{}" {paint}/>"#,
            poly(&[(0.0, -1.2), (1.05, 0.6), (-1.05, 0.6)])
        ),
        "rect" => write!(
            out,
            r#"<rect x="{}" y="{}" width="{}" height="{}" {paint}/>"#,
            n(x - r * 0.85),
            n(y - r * 0.85),
            n(r * 1.7),
            n(r * 1.7)
        ),
        "rectRot" => write!(
            out,
            r#"<polygon points="{}" {paint}/>"#,
            poly(&[(0.0, -1.2), (1.2, 0.0), (0.0, 1.2), (-1.2, 0.0)])
        ),
        "star" => {
            let pts: Vec<(f64, f64)> = (0..10)
                .map(|k| {
                    let a = std::f64::consts::PI * k as f64 / 5.0;
                    let rr = if k % 2 == 0 { 1.25 } else { 0.55 };
                    (rr * a.sin(), -rr * a.cos())
                })
                .collect();
            write!(out, r#"<polygon points="{}" {paint}/>"#, poly(&pts))
        }
        "crossRot" => write!(
            out,
            r#"<path d="M{} {}L{} {}M{} {}L{} {}" stroke="{color}" stroke-width="1.6" fill="none"/>"#,
            n(x - r),
            n(y - r),
            n(x + r),
            n(y + r),
            n(x - r),
            n(y + r),
            n(x + r),
            n(y - r)
        ),
        _ => write!(
            out,
            r#"<circle cx="{}" cy="{}" r="{}" {paint}/>"#,
            n(x),
            n(y),
            n(r)
        ),
    };
}

/// Legend entries laid out in rows across the figure's width.
fn legend_rows(entries: &[LegendEntry]) -> Vec<Vec<(f64, &LegendEntry)>> {
    let mut rows: Vec<Vec<(f64, &LegendEntry)>> = vec![Vec::new()];
    let mut x = 12.0;
    for e in entries {
        let w = 26.0 + text_width(&e.text, LEGEND_PT) + 14.0;
        if x + w > WIDTH - 8.0 && !rows.last().is_some_and(|r| r.is_empty()) {
            rows.push(Vec::new());
            x = 12.0;
        }
        rows.last_mut().expect("a row").push((x, e));
        x += w;
    }
    rows.retain(|r| !r.is_empty());
    rows
}

fn legend(out: &mut String, entries: &[LegendEntry], top: f64) {
    out.push_str(r#"<g class="legend-box">"#);
    for (i, row) in legend_rows(entries).iter().enumerate() {
        let y = top + i as f64 * LEGEND_ROW;
        for &(x, e) in row {
            match e.swatch {
                Swatch::Box { alpha } => {
                    let _ = write!(
                        out,
                        r#"<rect x="{}" y="{}" width="18" height="10" fill="{c}" fill-opacity="{}" stroke="{c}"/>"#,
                        n(x),
                        n(y - 9.0),
                        n(alpha),
                        c = e.color
                    );
                }
                Swatch::Line { dash } => {
                    let _ = write!(
                        out,
                        r#"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="{}" stroke-width="2"{}/>"#,
                        n(x),
                        n(y - 4.0),
                        n(x + 20.0),
                        n(y - 4.0),
                        e.color,
                        dash_attr(dash)
                    );
                }
                Swatch::Marker { marker: m, filled } => marker(
                    out,
                    m,
                    x + 9.0,
                    y - 4.0,
                    4.5,
                    e.color,
                    if filled { 0.8 } else { 0.0 },
                ),
            }
            text(
                out,
                x + 26.0,
                y,
                LEGEND_PT,
                "start",
                r#" class="legend""#,
                &e.text,
            );
        }
    }
    out.push_str("</g>");
}

/// About five round tick values covering [lo, hi]: multiples of 1, 2, 2.5 or 5 × 10^e,
/// computed as integers scaled by a power of ten so that 3 × 0.2 is 0.6.
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let span = (hi - lo).max(1e-9);
    let e = (span / 5.0).log10().floor() as i32;
    let mag = 10f64.powi(e);
    let m = [1.0, 2.0, 2.5, 5.0, 10.0]
        .into_iter()
        .find(|m| span / (m * mag) <= 6.0)
        .unwrap_or(10.0);
    let at = |k: f64| {
        if e < 0 {
            k * m / 10f64.powi(-e)
        } else {
            k * m * mag
        }
    };
    let step = m * mag;
    let mut k = (lo / step).ceil();
    let mut out = Vec::new();
    while at(k) <= hi + step * 1e-6 {
        out.push(at(k) + 0.0);
        k += 1.0;
    }
    out
}

fn tick_label(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        format!("{v:e}")
    } else {
        n(v)
    }
}

/// The data's range along an axis, padded, or `fixed`.
fn range(fixed: Option<[f64; 2]>, values: impl Iterator<Item = f64>, from_zero: bool) -> [f64; 2] {
    if let Some(r) = fixed {
        return r;
    }
    let (mut lo, mut hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return [0.0, 1.0];
    }
    if from_zero {
        lo = lo.min(0.0);
    }
    if hi - lo < 1e-9 {
        hi = lo + 1.0;
    }
    let pad = if from_zero { 0.0 } else { 0.05 * (hi - lo) };
    [lo - pad, hi + 0.05 * (hi - lo)]
}

/// A figure as a standalone SVG document.
pub fn figure_svg(f: &Figure) -> String {
    let rows = legend_rows(&f.legend).len() as f64;
    let plot_h = if f.kind == FigureKind::Radar {
        320.0
    } else {
        250.0
    };
    let rotate = matches!(f.kind, FigureKind::Bars | FigureKind::LogBars) && {
        let slot = (WIDTH - 80.0) / f.categories.len().max(1) as f64;
        f.categories
            .iter()
            .any(|c| text_width(c, TICK_PT) > slot - 4.0)
    };
    let below = match f.kind {
        FigureKind::Radar => 8.0,
        _ if rotate => 84.0,
        _ => 44.0,
    };
    let top = 36.0;
    // The legend's first baseline sits one row below `below`.
    let height = top + plot_h + below + rows * LEGEND_ROW + 14.0;
    let mut out = String::new();
    let _ = write!(
        out,
        r#"<?xml version="1.0" encoding="UTF-8"?>
<svg xmlns="http://www.w3.org/2000/svg" width="{w}pt" height="{h}pt" viewBox="0 0 {w} {h}" font-family="{FONT}">"#,
        w = n(WIDTH),
        h = n(height)
    );
    let _ = write!(
        out,
        "<title>{}</title><desc>{}</desc>",
        escape(&f.title),
        escape(&f.caption)
    );
    let _ = write!(
        out,
        r#"<rect width="{}" height="{}" fill="white"/>"#,
        n(WIDTH),
        n(height)
    );
    text(
        &mut out,
        WIDTH / 2.0,
        20.0,
        TITLE_PT,
        "middle",
        r#" font-weight="bold" class="title""#,
        &f.title,
    );
    match f.kind {
        FigureKind::Radar => radar(&mut out, f, top, plot_h),
        FigureKind::Scatter | FigureKind::Lines => xy(&mut out, f, top, plot_h),
        FigureKind::Bars | FigureKind::LogBars => bars(&mut out, f, top, plot_h, rotate),
    }
    legend(&mut out, &f.legend, top + plot_h + below + 14.0);
    out.push_str("</svg>\n");
    out
}

fn series_open(out: &mut String, d: &Dataset) {
    let _ = write!(
        out,
        r#"<g class="series" data-policy="{}" data-label="{}">"#,
        escape(&d.policy),
        escape(&d.label)
    );
}

fn radar(out: &mut String, f: &Figure, top: f64, h: f64) {
    let [lo, hi] = f.y_range.unwrap_or([0.0, 100.0]);
    let (cx, cy, r) = (WIDTH / 2.0, top + h / 2.0 + 4.0, h / 2.0 - 30.0);
    let k = f.categories.len().max(1);
    let at = |i: usize, v: f64| {
        let a = std::f64::consts::TAU * i as f64 / k as f64;
        let rr = r * ((v - lo) / (hi - lo)).clamp(0.0, 1.0);
        (cx + rr * a.sin(), cy - rr * a.cos())
    };
    let levels = ticks(lo, hi);
    for &v in &levels {
        let pts: Vec<String> = (0..k)
            .map(|i| {
                let (x, y) = at(i, v);
                format!("{},{}", n(x), n(y))
            })
            .collect();
        let _ = write!(
            out,
            r#"<polygon points="{}" fill="none" stroke="{GRID}"/>"#,
            pts.join(" ")
        );
    }
    for (i, c) in f.categories.iter().enumerate() {
        let (x, y) = at(i, hi);
        let _ = write!(
            out,
            r#"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="{GRID}"/>"#,
            n(cx),
            n(cy),
            n(x),
            n(y)
        );
        let (lx, ly) = {
            let a = std::f64::consts::TAU * i as f64 / k as f64;
            (cx + (r + 10.0) * a.sin(), cy - (r + 10.0) * a.cos())
        };
        let anchor = if lx > cx + 1.0 {
            "start"
        } else if lx < cx - 1.0 {
            "end"
        } else {
            "middle"
        };
        let dy = if ly < cy - r * 0.9 {
            -4.0
        } else if ly > cy + r * 0.9 {
            LABEL_PT
        } else {
            4.0
        };
        text(
            out,
            lx,
            ly + dy,
            LABEL_PT,
            anchor,
            r#" class="category""#,
            c,
        );
    }
    for d in &f.datasets {
        series_open(out, d);
        let pts: Vec<(f64, f64)> = d
            .values
            .iter()
            .enumerate()
            .filter_map(|(i, v)| v.map(|v| at(i, v)))
            .collect();
        let _ = write!(
            out,
            r#"<polygon points="{}" fill="{c}" fill-opacity="{}" stroke="{c}" stroke-width="2"{}/>"#,
            pts.iter()
                .map(|(x, y)| format!("{},{}", n(*x), n(*y)))
                .collect::<Vec<_>>()
                .join(" "),
            n(d.fill_alpha),
            dash_attr(d.dash),
            c = d.color
        );
        for &(x, y) in &pts {
            marker(out, d.marker, x, y, 3.0, d.color, 1.0);
        }
        out.push_str("</g>");
    }
    // Tick labels last, on a white backdrop, beside the upward spoke: the data never
    // crosses them.
    for &v in levels.iter().filter(|v| **v > lo) {
        let (_, y) = at(0, v);
        let label = tick_label(v);
        let w = text_width(&label, TICK_PT) + 4.0;
        let _ = write!(
            out,
            r#"<rect x="{}" y="{}" width="{}" height="{}" fill="white" fill-opacity="0.9" rx="2"/>"#,
            n(cx + 3.0),
            n(y - TICK_PT * 0.5),
            n(w),
            n(TICK_PT + 1.0)
        );
        text(
            out,
            cx + 5.0,
            y + TICK_PT * 0.4,
            TICK_PT,
            "start",
            r#" class="tick""#,
            &label,
        );
    }
}

/// Plot box: left, top, width, height.
struct PlotBox {
    x: f64,
    y: f64,
    w: f64,
    h: f64,
}

fn axes(out: &mut String, f: &Figure, b: &PlotBox, y_ticks: &[(f64, String)]) {
    for (py, label) in y_ticks {
        let _ = write!(
            out,
            r#"<line x1="{}" y1="{y}" x2="{}" y2="{y}" stroke="{GRID}"/>"#,
            n(b.x),
            n(b.x + b.w),
            y = n(*py)
        );
        text(
            out,
            b.x - 5.0,
            py + 4.0,
            TICK_PT,
            "end",
            r#" class="tick""#,
            label,
        );
    }
    let _ = write!(
        out,
        r#"<rect x="{}" y="{}" width="{}" height="{}" fill="none" stroke="{INK}" stroke-width="0.8"/>"#,
        n(b.x),
        n(b.y),
        n(b.w),
        n(b.h)
    );
    let (yx, yy) = (14.0, b.y + b.h / 2.0);
    text(
        out,
        yx,
        yy,
        LABEL_PT,
        "middle",
        &format!(r#" transform="rotate(-90 {} {})""#, n(yx), n(yy)),
        &f.y_label,
    );
}

fn xy(out: &mut String, f: &Figure, top: f64, h: f64) {
    let b = PlotBox {
        x: 64.0,
        y: top,
        w: WIDTH - 80.0,
        h,
    };
    let pts = || f.datasets.iter().flat_map(|d| d.points.iter());
    let [x0, x1] = range(f.x_range, pts().map(|p| p[0]), false);
    let [y0, y1] = range(f.y_range, pts().map(|p| p[1]), false);
    let px = |x: f64| b.x + (x - x0) / (x1 - x0) * b.w;
    let py = |y: f64| b.y + b.h - (y - y0) / (y1 - y0) * b.h;
    let yt: Vec<(f64, String)> = ticks(y0, y1)
        .into_iter()
        .map(|v| (py(v), tick_label(v)))
        .collect();
    axes(out, f, &b, &yt);
    for v in ticks(x0, x1) {
        text(
            out,
            px(v),
            b.y + b.h + 15.0,
            TICK_PT,
            "middle",
            r#" class="tick""#,
            &tick_label(v),
        );
    }
    text(
        out,
        b.x + b.w / 2.0,
        b.y + b.h + 37.0,
        LABEL_PT,
        "middle",
        "",
        &f.x_label,
    );
    for d in &f.datasets {
        series_open(out, d);
        if f.kind == FigureKind::Lines {
            let _ = write!(
                out,
                r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="2"{}/>"#,
                d.points
                    .iter()
                    .map(|p| format!("{},{}", n(px(p[0])), n(py(p[1]))))
                    .collect::<Vec<_>>()
                    .join(" "),
                d.color,
                dash_attr(d.dash)
            );
        }
        let r = if f.kind == FigureKind::Scatter {
            4.0
        } else {
            3.5
        };
        for p in &d.points {
            marker(out, d.marker, px(p[0]), py(p[1]), r, d.color, d.fill_alpha);
        }
        out.push_str("</g>");
    }
}

fn bars(out: &mut String, f: &Figure, top: f64, h: f64, rotate: bool) {
    let b = PlotBox {
        x: 64.0,
        y: top,
        w: WIDTH - 80.0,
        h,
    };
    let log = f.kind == FigureKind::LogBars;
    let values = || {
        f.datasets
            .iter()
            .flat_map(|d| d.values.iter().flatten().copied())
    };
    let (y0, y1, yt): (f64, f64, Vec<f64>) = if log {
        let pos = || values().filter(|v| *v > 0.0);
        let lo = pos().fold(f64::INFINITY, f64::min);
        let hi = pos().fold(0.0, f64::max);
        let (lo, hi) = if lo.is_finite() {
            (
                lo.log10().floor(),
                hi.log10().ceil().max(lo.log10().floor() + 1.0),
            )
        } else {
            (0.0, 1.0)
        };
        let t = (lo as i32..=hi as i32).map(f64::from).collect();
        (lo, hi, t)
    } else {
        let [lo, hi] = range(f.y_range, values(), true);
        (lo, hi, ticks(lo, hi))
    };
    let scale = |v: f64| if log { v.max(1e-300).log10() } else { v };
    let py = |v: f64| b.y + b.h - ((scale(v) - y0) / (y1 - y0)).clamp(0.0, 1.0) * b.h;
    let labels: Vec<(f64, String)> = yt
        .iter()
        .map(|&t| {
            if log {
                (py(10f64.powf(t)), tick_label(10f64.powf(t)))
            } else {
                (py(t), tick_label(t))
            }
        })
        .collect();
    axes(out, f, &b, &labels);
    let k = f.categories.len().max(1);
    let slot = b.w / k as f64;
    for (i, c) in f.categories.iter().enumerate() {
        let x = b.x + slot * (i as f64 + 0.5);
        let y = b.y + b.h + 15.0;
        if rotate {
            let extra = format!(
                r#" class="category" transform="rotate(-35 {} {})""#,
                n(x),
                n(y)
            );
            text(out, x, y, TICK_PT, "end", &extra, c);
        } else {
            text(out, x, y, TICK_PT, "middle", r#" class="category""#, c);
        }
    }
    let below = if rotate { 76.0 } else { 34.0 };
    text(
        out,
        b.x + b.w / 2.0,
        b.y + b.h + below,
        LABEL_PT,
        "middle",
        "",
        &f.x_label,
    );
    let m = f.datasets.len().max(1) as f64;
    let bar = slot * 0.8 / m;
    let base = if log { b.y + b.h } else { py(0.0) };
    for (j, d) in f.datasets.iter().enumerate() {
        series_open(out, d);
        for (i, v) in d.values.iter().enumerate() {
            let Some(v) = v else { continue };
            let x = b.x + slot * i as f64 + slot * 0.1 + bar * j as f64;
            let y = py(*v);
            let _ = write!(
                out,
                r#"<rect x="{}" y="{}" width="{}" height="{}" fill="{c}" fill-opacity="{}" stroke="{c}" stroke-width="0.8"/>"#,
                n(x),
                n(y.min(base)),
                n(bar),
                n((base - y).abs()),
                n(d.fill_alpha),
                c = d.color
            );
        }
        out.push_str("</g>");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_cover_the_range() {
        assert_eq!(ticks(0.0, 100.0), vec![0.0, 20.0, 40.0, 60.0, 80.0, 100.0]);
        assert_eq!(ticks(0.0, 1.0), vec![0.0, 0.2, 0.4, 0.6, 0.8, 1.0]);
        let t = ticks(-0.05, 1.05);
        assert_eq!(t.first(), Some(&0.0));
        assert!((t.last().unwrap() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn numbers_are_short() {
        assert_eq!(n(1.0), "1");
        assert_eq!(n(1.256), "1.26");
        assert_eq!(n(-0.001), "0");
    }
}
