//! The report's figures as data: for each chart what it plots, in which colour, dash and
//! marker, and what its legend says. The page script draws these with Chart.js and
//! [`super::svg`] writes them as SVG files, so the HTML and the vector figures agree by
//! construction.

use super::runs::{EpisodePoint, Run};
use super::style::{jitter, PolicyColors, DASHES, DASH_NAMES, KEY_COLOR, SURVIVAL_JITTER};
use super::tables::all_tasks;
use serde::Serialize;

/// A line chart of a sweep, as `sweep collect` computes it: a metric against a swept
/// quantity (force coefficient, push, latency budget), one line per policy and value of
/// the sweep's other varying axes.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SweepChart {
    /// Canvas id, and the SVG file's stem.
    pub id: String,
    /// Caption.
    pub title: String,
    /// x axis label, with unit.
    pub x_label: String,
    /// y axis label.
    pub y_label: String,
    /// The lines.
    pub series: Vec<CurveSeries>,
}

/// One line of a [`SweepChart`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CurveSeries {
    /// Full label (policy and other axes), for tooltips.
    pub label: String,
    /// The policy: the line's colour.
    pub policy: String,
    /// The values of the sweep's other varying axes (`""` when none varies): the line's
    /// dash.
    pub variant: String,
    /// `[x, y]`, sorted by x.
    pub points: Vec<[f64; 2]>,
}

/// How a figure is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FigureKind {
    /// One polygon per dataset over `categories` (FATS per task).
    Radar,
    /// Points only.
    Scatter,
    /// Points joined by lines.
    Lines,
    /// Grouped bars per category.
    Bars,
    /// Grouped bars on a logarithmic y axis.
    LogBars,
}

/// A legend entry's sample.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Swatch {
    /// A filled box at this opacity.
    Box {
        /// Fill opacity.
        alpha: f64,
    },
    /// A line in [`DASHES`]`[dash]`.
    Line {
        /// Dash index.
        dash: usize,
    },
    /// A marker ([`super::style::MARKERS`]`[marker]`), filled or hollow.
    Marker {
        /// Marker index.
        marker: usize,
        /// Filled, or outline only.
        filled: bool,
    },
}

/// One legend entry: what a colour, dash or marker stands for.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LegendEntry {
    /// The text.
    pub text: String,
    /// The sample's colour.
    pub color: &'static str,
    /// The sample.
    pub swatch: Swatch,
}

/// One dataset of a figure.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Dataset {
    /// Label (tooltips).
    pub label: String,
    /// The policy it belongs to.
    pub policy: String,
    /// The policy's colour.
    pub color: &'static str,
    /// Index into [`DASHES`].
    pub dash: usize,
    /// Index into [`super::style::MARKERS`].
    pub marker: usize,
    /// Fill opacity (radar area, marker, bar); 0 draws outlines only.
    pub fill_alpha: f64,
    /// Per category (radar, bars); `None` where there is no value.
    pub values: Vec<Option<f64>>,
    /// `[x, y]` (scatter, lines).
    pub points: Vec<[f64; 2]>,
    /// Scatter: the episode (index into [`ReportFigures::episodes`]) of each point.
    pub episodes: Vec<usize>,
}

/// One chart.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Figure {
    /// Canvas id and SVG file stem (letters, digits, `-`).
    pub id: String,
    /// Short title (the SVG's heading).
    pub title: String,
    /// Caption under the title in the page.
    pub caption: String,
    /// How it is drawn.
    pub kind: FigureKind,
    /// Radar spokes or bar groups.
    pub categories: Vec<String>,
    /// x axis label.
    pub x_label: String,
    /// y axis label (the radial axis of a radar).
    pub y_label: String,
    /// Fixed x range, else the data's.
    pub x_range: Option<[f64; 2]>,
    /// Fixed y range, else the data's (bars from zero).
    pub y_range: Option<[f64; 2]>,
    /// The data.
    pub datasets: Vec<Dataset>,
    /// The legend.
    pub legend: Vec<LegendEntry>,
}

/// Every figure of a report, by section.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportFigures {
    /// A sweep's curves (empty for `report`).
    pub sweep: Vec<Figure>,
    /// FATS per task, one radar per setting.
    pub radars: Vec<Figure>,
    /// Tracking against survival, one point per episode.
    pub scatter: Figure,
    /// Low- and high-force keypoint error per task, one per setting.
    pub regimes: Vec<Figure>,
    /// Policy-server latency percentiles and faults (empty without such runs).
    pub latency: Vec<Figure>,
    /// The scatter's episodes.
    pub episodes: Vec<EpisodePoint>,
}

impl ReportFigures {
    /// Every figure, in page order.
    pub fn all(&self) -> impl Iterator<Item = &Figure> {
        self.sweep
            .iter()
            .chain(&self.radars)
            .chain(std::iter::once(&self.scatter))
            .chain(&self.regimes)
            .chain(&self.latency)
    }
}

/// An id fragment from a setting name (`push-30.5` → `push-30-5`).
pub(super) fn slug(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .collect()
}

/// Setting names in the runs' order.
pub(super) fn settings_of(runs: &[Run]) -> Vec<String> {
    let mut settings: Vec<String> = Vec::new();
    for r in runs {
        for s in r.settings() {
            if !settings.contains(&s) {
                settings.push(s);
            }
        }
    }
    settings
}

/// The runs holding `setting`, each with its dash: the k-th run of a policy there gets
/// dash k, so two runs of one policy on one chart differ by line style.
fn runs_with(runs: &[Run], setting: &str) -> Vec<(usize, usize)> {
    let mut seen: Vec<&str> = Vec::new();
    runs.iter()
        .enumerate()
        .filter(|(_, r)| r.results.contains_key(setting))
        .map(|(i, r)| {
            let dash = seen.iter().filter(|p| **p == r.header.policy).count();
            seen.push(&r.header.policy);
            (i, dash % DASHES.len())
        })
        .collect()
}

fn dataset(label: String, policy: &str, colors: &PolicyColors) -> Dataset {
    Dataset {
        label,
        policy: policy.to_string(),
        color: colors.get(policy),
        dash: 0,
        marker: 0,
        fill_alpha: 1.0,
        values: Vec::new(),
        points: Vec::new(),
        episodes: Vec::new(),
    }
}

fn figure(id: String, title: String, caption: String, kind: FigureKind) -> Figure {
    Figure {
        id,
        title,
        caption,
        kind,
        categories: Vec::new(),
        x_label: String::new(),
        y_label: String::new(),
        x_range: None,
        y_range: None,
        datasets: Vec::new(),
        legend: Vec::new(),
    }
}

/// One entry per dataset: its label in its colour and dash.
fn line_legend(datasets: &[Dataset]) -> Vec<LegendEntry> {
    datasets
        .iter()
        .map(|d| LegendEntry {
            text: d.label.clone(),
            color: d.color,
            swatch: Swatch::Line { dash: d.dash },
        })
        .collect()
}

/// The figures of a report on `runs`, with a sweep's curves first.
pub fn report_figures(runs: &[Run], sweep: &[SweepChart]) -> ReportFigures {
    let colors = PolicyColors::new(
        runs.iter().map(|r| r.header.policy.as_str()).chain(
            sweep
                .iter()
                .flat_map(|c| c.series.iter().map(|s| s.policy.as_str())),
        ),
    );
    let tasks = all_tasks(runs);
    let settings = settings_of(runs);
    let per_task = |r: &Run, s: &str, f: fn(&crate::eval::metrics::Diagnostics) -> f64| {
        tasks
            .iter()
            .map(|t| {
                r.task(s, t)
                    .map(|t| f(&t.diagnostics))
                    .filter(|v| v.is_finite())
            })
            .collect::<Vec<_>>()
    };
    let radars = settings
        .iter()
        .map(|s| {
            let mut f = figure(
                format!("radar-{}", slug(s)),
                format!("FATS per task — {s}"),
                format!("FATS per task — {s}"),
                FigureKind::Radar,
            );
            f.categories = tasks.clone();
            f.y_label = "FATS".into();
            f.y_range = Some([0.0, 100.0]);
            f.datasets = runs_with(runs, s)
                .into_iter()
                .map(|(i, dash)| Dataset {
                    dash,
                    fill_alpha: 0.12,
                    values: per_task(&runs[i], s, |d| d.fats),
                    ..dataset(runs[i].label.clone(), &runs[i].header.policy, &colors)
                })
                .collect();
            f.legend = line_legend(&f.datasets);
            f
        })
        .collect();
    let regimes = settings
        .iter()
        .map(|s| {
            let mut f = figure(
                format!("kp-regimes-{}", slug(s)),
                format!("Keypoint RMSE, low vs high force — {s}"),
                format!("Low- vs high-force keypoint RMSE per task (mm) — {s}; pale: low force, solid: high force"),
                FigureKind::Bars,
            );
            f.categories = tasks.clone();
            f.y_label = "keypoint RMSE (mm)".into();
            for (i, _) in runs_with(runs, s) {
                let r = &runs[i];
                for (name, alpha, values) in [
                    ("low force", 0.35, per_task(r, s, |d| d.low_kp_mm)),
                    ("high force", 1.0, per_task(r, s, |d| d.high_kp_mm)),
                ] {
                    f.datasets.push(Dataset {
                        fill_alpha: alpha,
                        values,
                        ..dataset(format!("{} — {name}", r.label), &r.header.policy, &colors)
                    });
                }
                f.legend.push(LegendEntry {
                    text: r.label.clone(),
                    color: colors.get(&r.header.policy),
                    swatch: Swatch::Box { alpha: 1.0 },
                });
            }
            for (text, alpha) in [("low force (pale)", 0.35), ("high force (solid)", 1.0)] {
                f.legend.push(LegendEntry {
                    text: text.into(),
                    color: KEY_COLOR,
                    swatch: Swatch::Box { alpha },
                });
            }
            f
        })
        .collect();
    let episodes: Vec<EpisodePoint> = runs
        .iter()
        .enumerate()
        .flat_map(|(i, r)| r.episode_points(i))
        .collect();
    let mut figures = ReportFigures {
        sweep: sweep.iter().map(|c| sweep_figure(c, &colors)).collect(),
        radars,
        scatter: scatter(runs, &settings, &episodes, &colors),
        regimes,
        latency: latency(runs, &colors),
        episodes,
    };
    // A figure copied into a paper keeps what it measured: engine and dataset.
    if let Some(context) = measured_on(runs) {
        for f in figures
            .radars
            .iter_mut()
            .chain(figures.regimes.iter_mut())
            .chain(figures.latency.iter_mut())
            .chain(std::iter::once(&mut figures.scatter))
        {
            f.title = format!("{} — {context}", f.title);
        }
    }
    figures
}

/// The engines and datasets of `runs`, as a figure's title names them (`rapier,
/// dataset synthetic`); `None` without runs.
fn measured_on(runs: &[Run]) -> Option<String> {
    let mut engines: Vec<String> = runs.iter().map(|r| r.header.engine_label()).collect();
    let mut datasets: Vec<String> = runs
        .iter()
        .map(|r| dataset_name(&r.header.dataset))
        .collect();
    for list in [&mut engines, &mut datasets] {
        list.sort();
        list.dedup();
    }
    (!runs.is_empty()).then(|| {
        format!(
            "{}, dataset{} {}",
            engines.join(" / "),
            if datasets.len() > 1 { "s" } else { "" },
            datasets.join(" / ")
        )
    })
}

/// The last part of a dataset's path (`/x/cache/sample` → `sample`).
fn dataset_name(path: &str) -> String {
    std::path::Path::new(path)
        .file_name()
        .map_or_else(|| path.to_string(), |n| n.to_string_lossy().into_owned())
}

/// Tracking against survival: colour per policy, marker per setting, hollow markers for a
/// second run of a policy, survival jittered so equal values stay visible.
fn scatter(
    runs: &[Run],
    settings: &[String],
    episodes: &[EpisodePoint],
    colors: &PolicyColors,
) -> Figure {
    let mut f = figure(
        "scatter-tracking-survival".into(),
        "Tracking vs survival, one point per episode".into(),
        format!(
            "One point per episode: tracking score 100·exp(−E/σ) against survival; colour: policy, marker: setting (hollow: a second run of the same policy). Survival is jittered by up to ±{SURVIVAL_JITTER} (deterministic per episode) so that episodes at the same survival, often 1.0, do not hide each other; tooltips give the exact value."
        ),
        FigureKind::Scatter,
    );
    f.x_label = format!("survival (jittered ±{SURVIVAL_JITTER})");
    f.y_label = "tracking score 100·exp(−E/σ)".into();
    f.x_range = Some([-0.05, 1.05]);
    f.y_range = Some([0.0, 100.0]);
    let mut hollow: Vec<usize> = Vec::new();
    for (m, s) in settings.iter().enumerate() {
        for (run, dash) in runs_with(runs, s) {
            let r = &runs[run];
            let mut d = Dataset {
                marker: m % super::style::MARKERS.len(),
                fill_alpha: if dash == 0 { 0.6 } else { 0.0 },
                ..dataset(format!("{} — {s}", r.label), &r.header.policy, colors)
            };
            for (k, e) in episodes.iter().enumerate() {
                if e.run == run && &e.setting == s {
                    let key = format!("{}/{}/{}", e.setting, e.task, e.sequence_id);
                    d.points
                        .push([e.survival + SURVIVAL_JITTER * jitter(&key), e.tracking]);
                    d.episodes.push(k);
                }
            }
            if dash > 0 && !hollow.contains(&run) {
                hollow.push(run);
            }
            if !d.points.is_empty() {
                f.datasets.push(d);
            }
        }
    }
    let mut policies: Vec<&str> = f.datasets.iter().map(|d| d.policy.as_str()).collect();
    policies.sort_unstable();
    policies.dedup();
    for p in policies {
        f.legend.push(LegendEntry {
            text: p.to_string(),
            color: colors.get(p),
            swatch: Swatch::Box { alpha: 1.0 },
        });
    }
    for (m, s) in settings.iter().enumerate() {
        f.legend.push(LegendEntry {
            text: format!("setting {s}"),
            color: KEY_COLOR,
            swatch: Swatch::Marker {
                marker: m % super::style::MARKERS.len(),
                filled: true,
            },
        });
    }
    for run in hollow {
        f.legend.push(LegendEntry {
            text: format!("hollow: {}", runs[run].label),
            color: colors.get(&runs[run].header.policy),
            swatch: Swatch::Marker {
                marker: 0,
                filled: false,
            },
        });
    }
    f
}

fn latency(runs: &[Run], colors: &PolicyColors) -> Vec<Figure> {
    let io: Vec<&Run> = runs
        .iter()
        .filter(|r| {
            r.policy_io
                .as_ref()
                .is_some_and(|io| io.transport.is_some())
        })
        .collect();
    if io.is_empty() {
        return Vec::new();
    }
    let mut p = figure(
        "latency-percentiles".into(),
        "Round-trip latency through the policy server".into(),
        "Round-trip latency percentiles through the policy server (µs, log scale; the run stores percentiles, not samples)".into(),
        FigureKind::LogBars,
    );
    p.categories = ["p50", "p90", "p99", "p99.9", "max"]
        .map(String::from)
        .to_vec();
    p.y_label = "round trip (µs)".into();
    let mut faults = figure(
        "latency-faults".into(),
        "Policy I/O faults".into(),
        "Deadline misses, late replies and invalid actions".into(),
        FigureKind::Bars,
    );
    faults.categories = [
        "deadline misses",
        "late replies",
        "invalid actions",
        "policy failures",
    ]
    .map(String::from)
    .to_vec();
    faults.y_label = "control steps".into();
    for r in io {
        let io = r.policy_io.as_ref().expect("filtered");
        let t = io.transport.expect("filtered");
        let l = &io.latency;
        p.datasets.push(Dataset {
            values: [l.p50_us, l.p90_us, l.p99_us, l.p999_us, l.max_us]
                .map(Some)
                .to_vec(),
            ..dataset(
                format!("{} ({} steps, mean {:.1} µs)", r.label, l.count, l.mean_us),
                &r.header.policy,
                colors,
            )
        });
        faults.datasets.push(Dataset {
            values: [
                io.deadline_misses,
                t.late_replies,
                io.invalid_actions,
                t.policy_failures,
            ]
            .map(|v| Some(v as f64))
            .to_vec(),
            ..dataset(r.label.clone(), &r.header.policy, colors)
        });
    }
    for f in [&mut p, &mut faults] {
        f.legend = f
            .datasets
            .iter()
            .map(|d| LegendEntry {
                text: d.label.clone(),
                color: d.color,
                swatch: Swatch::Box { alpha: 1.0 },
            })
            .collect();
    }
    vec![p, faults]
}

/// A sweep chart: colour per policy, dash per value of the other axes, and a legend with
/// one entry per policy and one per dash.
fn sweep_figure(c: &SweepChart, colors: &PolicyColors) -> Figure {
    let mut variants: Vec<&str> = c.series.iter().map(|s| s.variant.as_str()).collect();
    variants.sort_unstable();
    variants.dedup();
    let dash_of = |v: &str| variants.iter().position(|x| *x == v).unwrap_or(0) % DASHES.len();
    let mut f = figure(
        c.id.clone(),
        c.title.clone(),
        c.title.clone(),
        FigureKind::Lines,
    );
    if variants.len() > 1 {
        f.caption += &format!(
            "; colour: policy, line style: {}",
            variants
                .iter()
                .map(|v| format!("{} {v}", DASH_NAMES[dash_of(v)]))
                .collect::<Vec<_>>()
                .join(", ")
        );
    } else {
        f.caption += "; colour: policy";
    }
    f.x_label = c.x_label.clone();
    f.y_label = c.y_label.clone();
    f.datasets = c
        .series
        .iter()
        .map(|s| Dataset {
            dash: dash_of(&s.variant),
            points: s.points.clone(),
            ..dataset(s.label.clone(), &s.policy, colors)
        })
        .collect();
    let mut policies: Vec<&str> = c.series.iter().map(|s| s.policy.as_str()).collect();
    policies.sort_unstable();
    policies.dedup();
    for p in policies {
        f.legend.push(LegendEntry {
            text: p.to_string(),
            color: colors.get(p),
            swatch: Swatch::Box { alpha: 1.0 },
        });
    }
    if variants.len() > 1 {
        for v in &variants {
            f.legend.push(LegendEntry {
                text: v.to_string(),
                color: KEY_COLOR,
                swatch: Swatch::Line { dash: dash_of(v) },
            });
        }
    }
    f
}
