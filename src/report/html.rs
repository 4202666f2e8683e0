//! Assembling the self-contained pages: templates and styles from `web/src/` (compiled in,
//! they are ours and small), the data as inline JSON, and the page script from the
//! front-end bundle (`web/bundle/`, compiled in as well).

use super::figures::{report_figures, Figure, ReportFigures, SweepChart};
use super::runs::{comparison_notes, comparison_warnings, Run};
use super::scene::ViewScene;
use super::style::{DASHES, MARKERS};
use super::tables::{diagnostics_multi_table, fats_table};
use super::ReportError;
use serde::Serialize;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Environment variable naming a bundle directory to use instead of the compiled-in one
/// (for front-end work: `npm run build --prefix web -- --outdir=…` and no cargo rebuild).
pub const WEB_DIST_ENV: &str = "THORARENA_WEB_DIST";

const REPORT_TEMPLATE: &str = include_str!("../../web/src/report.html");
const REPORT_STYLE: &str = include_str!("../../web/src/report.css");
const VIEW_TEMPLATE: &str = include_str!("../../web/src/view.html");
const VIEW_STYLE: &str = include_str!("../../web/src/view.css");

/// The page scripts as built by `npm run build --prefix web` from `web/src/` and the
/// lockfile's three.js and Chart.js. Committed, so that building and running the binary
/// never needs node or the network; `tests/web_bundle.rs` rebuilds them from the lockfile
/// and fails if the committed copy differs by a byte.
const EMBEDDED_REPORT_JS: &str = include_str!("../../web/bundle/report.js");
const EMBEDDED_VIEW_JS: &str = include_str!("../../web/bundle/view.js");

/// The largest page script read from `THORARENA_WEB_DIST`, bytes (the bundled ones are
/// under 1 MiB).
const MAX_SCRIPT_BYTES: u64 = 32 * crate::files::bounded_read::MIB;

/// A page of the front end, one bundled script each.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Page {
    /// `thorarena report`.
    Report,
    /// `thorarena view`.
    View,
}

impl Page {
    fn script_name(self) -> &'static str {
        match self {
            Page::Report => "report.js",
            Page::View => "view.js",
        }
    }

    fn embedded_script(self) -> &'static str {
        match self {
            Page::Report => EMBEDDED_REPORT_JS,
            Page::View => EMBEDDED_VIEW_JS,
        }
    }
}

/// The front-end bundle: our page scripts with three.js and Chart.js.
#[derive(Debug, Clone)]
pub enum WebBundle {
    /// The copy compiled into this binary (the default): works offline, from any
    /// directory, with no checkout beside the binary.
    Embedded,
    /// A directory holding `report.js` and `view.js`, named by [`WEB_DIST_ENV`].
    Dir(PathBuf),
}

impl WebBundle {
    /// The bundle of [`WEB_DIST_ENV`] when it is set, else the compiled-in one.
    pub fn locate() -> Result<Self, ReportError> {
        match std::env::var_os(WEB_DIST_ENV) {
            Some(dir) => Self::at(Path::new(&dir)),
            None => Ok(Self::Embedded),
        }
    }

    /// The bundle in `dir`; an error naming the build command when a script is missing.
    pub fn at(dir: &Path) -> Result<Self, ReportError> {
        for page in [Page::Report, Page::View] {
            let path = dir.join(page.script_name());
            if !path.is_file() {
                return Err(ReportError::BundleMissing { path });
            }
        }
        Ok(Self::Dir(dir.to_path_buf()))
    }

    /// Where the scripts come from, for messages.
    pub fn describe(&self) -> String {
        match self {
            Self::Embedded => "the bundle compiled into this binary".into(),
            Self::Dir(dir) => dir.display().to_string(),
        }
    }

    /// A page's script, safe to inline in a `<script>` element.
    pub fn script(&self, page: Page) -> Result<String, ReportError> {
        match self {
            Self::Embedded => Ok(inline_script(page.embedded_script())),
            Self::Dir(dir) => {
                let path = dir.join(page.script_name());
                let text = crate::files::bounded_read::read_to_string(
                    &path,
                    "page script",
                    MAX_SCRIPT_BYTES,
                )
                .map_err(|source| ReportError::Io {
                    path: path.clone(),
                    source,
                })?;
                Ok(inline_script(&text))
            }
        }
    }

    /// A warning per stale source ([`WebBundle::stale_sources`]), saying how to rebuild.
    pub fn stale_warnings(&self) -> Vec<String> {
        self.stale_sources()
            .iter()
            .map(|stale| {
                format!(
                    "warning: {} is newer than the bundle in {}; rebuild it with `npm run build --prefix web -- --outdir={}`",
                    stale.display(),
                    self.describe(),
                    self.describe()
                )
            })
            .collect()
    }

    /// Front-end sources newer than a bundle directory (`web/src/*.js` next to it): the
    /// page would run old code, so the CLI warns. The compiled-in bundle is checked
    /// against its sources by `tests/web_bundle.rs` instead (file times say nothing
    /// after a fresh clone).
    pub fn stale_sources(&self) -> Vec<PathBuf> {
        let Self::Dir(dir) = self else {
            return Vec::new();
        };
        let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
        let built = [Page::Report, Page::View]
            .iter()
            .filter_map(|p| modified(&dir.join(p.script_name())))
            .min();
        let (Some(built), Some(web)) = (built, dir.parent()) else {
            return Vec::new();
        };
        let Ok(entries) = std::fs::read_dir(web.join("src")) else {
            return Vec::new();
        };
        let mut stale: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "js"))
            .filter(|p| modified(p).is_some_and(|m| m > built))
            .collect();
        stale.sort();
        stale
    }
}

/// HTML-escapes text for element content and quoted attributes.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A script's text made safe inside `<script>…</script>`: the only sequence that ends the
/// element early is `</script`, and `<\/script` means the same in JS strings, regular
/// expressions and comments (esbuild already writes it so; this guards hand-built
/// bundles).
fn inline_script(js: &str) -> String {
    let mut out = String::with_capacity(js.len());
    let lower = js.to_ascii_lowercase();
    let mut last = 0;
    for (i, _) in lower.match_indices("</script") {
        out.push_str(&js[last..i]);
        out.push_str("<\\/");
        last = i + 2;
    }
    out.push_str(&js[last..]);
    out
}

/// JSON for a `<script type="application/json">` element: `<` is written as `\u003c`,
/// which JSON.parse reads back unchanged, so no string in the data can close the element.
fn inline_json<T: Serialize>(value: &T) -> String {
    serde_json::to_string(value)
        .expect("report data serializes")
        .replace('<', "\\u003c")
}

/// Fills `{{name}}` placeholders in one pass, so text inserted for one placeholder is
/// never searched for another.
fn fill(template: &str, values: &[(&str, &str)]) -> String {
    let mut out =
        String::with_capacity(template.len() + values.iter().map(|v| v.1.len()).sum::<usize>());
    let mut rest = template;
    while let Some(start) = rest.find("{{") {
        let Some(len) = rest[start + 2..].find("}}") else {
            break;
        };
        let name = &rest[start + 2..start + 2 + len];
        match values.iter().find(|(n, _)| *n == name) {
            Some((_, v)) => {
                out.push_str(&rest[..start]);
                out.push_str(v);
            }
            None => out.push_str(&rest[..start + 4 + len]),
        }
        rest = &rest[start + 4 + len..];
    }
    out.push_str(rest);
    out
}

#[derive(Serialize)]
struct RunInfo<'a> {
    label: &'a str,
    policy: &'a str,
    dir: String,
}

/// The styles the figures' indices refer to.
#[derive(Serialize)]
struct Styles {
    dashes: &'static [&'static [f64]],
    markers: &'static [&'static str],
}

/// Everything the report script plots; `plots` lists every canvas id it must fill.
#[derive(Serialize)]
struct ReportData<'a> {
    style: Styles,
    runs: Vec<RunInfo<'a>>,
    figures: Vec<&'a Figure>,
    episodes: &'a [super::runs::EpisodePoint],
    plots: Vec<String>,
}

fn fmt_opt(v: Option<f64>, decimals: usize) -> String {
    v.filter(|v| v.is_finite())
        .map_or("–".into(), |v| format!("{v:.decimals$}"))
}

/// The report page for `runs` (one or several) with the bundled `script` inlined.
pub fn report_html(runs: &[Run], script: &str) -> String {
    let title = format!(
        "ThorArena report — {}",
        runs.iter()
            .map(|r| r.label.as_str())
            .collect::<Vec<_>>()
            .join(" vs ")
    );
    page(runs, &report_figures(runs, &[]), &title, script)
}

/// The report page of a sweep titled `title` (the sweep's axes, e.g. "sweep: 2 policies ×
/// 4 force coefficients"): the sweep's curves first, then the comparison of its cells
/// (`runs`) as in [`report_html`].
pub fn sweep_report_html(runs: &[Run], sweep: &[SweepChart], title: &str, script: &str) -> String {
    page(runs, &report_figures(runs, sweep), title, script)
}

fn page(runs: &[Run], figures: &ReportFigures, title: &str, script: &str) -> String {
    let data = ReportData {
        style: Styles {
            dashes: &DASHES,
            markers: &MARKERS,
        },
        runs: runs
            .iter()
            .map(|r| RunInfo {
                label: &r.label,
                policy: &r.header.policy,
                dir: r.dir.display().to_string(),
            })
            .collect(),
        figures: figures.all().collect(),
        episodes: &figures.episodes,
        plots: figures.all().map(|f| f.id.clone()).collect(),
    };
    let body = report_body(runs, figures);
    fill(
        REPORT_TEMPLATE,
        &[
            ("title", &escape(title)),
            ("style", REPORT_STYLE),
            ("body", &body),
            ("data", &inline_json(&data)),
            ("script", script),
        ],
    )
}

fn figure(f: &Figure) -> String {
    format!(
        "<figure><figcaption>{}</figcaption><div class=\"chart\"><canvas id=\"{}\"></canvas></div></figure>",
        escape(&f.caption),
        escape(&f.id)
    )
}

/// The page body: runs, the comparability warnings, the tables, and one canvas per plot
/// (the script fills them).
fn report_body(runs: &[Run], data: &ReportFigures) -> String {
    let mut s = String::new();
    if !data.sweep.is_empty() {
        s += "<section id=\"sweep\"><h2>Sweep</h2><div class=\"grid\">";
        for f in &data.sweep {
            s += &figure(f);
        }
        s += "</div></section>";
    }
    s += "<section id=\"runs\"><h2>Runs</h2><table id=\"runs-table\"><thead><tr><th>run</th><th>policy</th><th>profile</th><th>engine</th><th>dataset</th><th>keypoints</th><th>termination</th><th>settings</th><th>episodes</th><th>directory</th></tr></thead><tbody>";
    for r in runs {
        let h = &r.header;
        let _ = write!(
            s,
            "<tr><th>{}</th><td>{}</td><td>{}</td><td>{}</td><td>{} <code>{}</code></td><td>{}</td><td>height &gt; {} m or tilt &gt; {} rad</td><td>{}</td><td>{}</td><td><code>{}</code></td></tr>",
            escape(&r.label),
            escape(&h.policy_text().replace('`', "")),
            escape(&h.profile),
            escape(&h.engine_label()),
            escape(&h.dataset),
            escape(&h.dataset_sha256[..h.dataset_sha256.len().min(12)]),
            escape(&h.keypoints),
            h.termination.max_torso_height_error_m,
            h.termination.max_torso_tilt_error_rad,
            escape(&r.settings().join(", ")),
            r.records.len(),
            escape(&r.dir.display().to_string())
        );
    }
    s += "</tbody></table></section>";
    let warnings = comparison_warnings(runs);
    if !warnings.is_empty() {
        s += "<section id=\"comparability-warnings\" class=\"warning\" role=\"alert\"><h2>⚠ These runs are not comparable as they stand</h2><ul>";
        for w in &warnings {
            let _ = write!(
                s,
                "<li data-kind=\"{}\">{}</li>",
                escape(
                    serde_json::to_value(w.kind)
                        .ok()
                        .and_then(|v| v.as_str().map(str::to_string))
                        .unwrap_or_default()
                        .as_str()
                ),
                escape(&w.message)
            );
        }
        s += "</ul><p>Numbers below are shown per run; differences between runs may come from these, not from the policies.</p></section>";
    }
    let notes = comparison_notes(runs);
    if !notes.is_empty() {
        s += "<section id=\"comparability-notes\"><ul>";
        for n in &notes {
            let _ = write!(s, "<li>Note: {}</li>", escape(n));
        }
        s += "</ul></section>";
    }
    let _ = write!(
        s,
        "<section id=\"tables\"><h2>Task-level FATS</h2>{}<h2>Diagnostics (averaged over tasks)</h2>{}</section>",
        fats_table(runs).html("fats-table"),
        diagnostics_multi_table(runs).html("diagnostics-table")
    );
    s += "<section id=\"plots\"><h2>FATS per task</h2><div class=\"grid\">";
    for f in &data.radars {
        s += &figure(f);
    }
    s += "</div><h2>Tracking vs survival</h2><div class=\"grid wide\">";
    s += &figure(&data.scatter);
    s += "</div><h2>Keypoint error under low and high force</h2><div class=\"grid\">";
    for f in &data.regimes {
        s += &figure(f);
    }
    s += "</div></section>";
    let io_runs: Vec<&Run> = runs.iter().filter(|r| r.policy_io.is_some()).collect();
    if !io_runs.is_empty() {
        s += "<section id=\"policy-io\"><h2>Policy I/O</h2><table id=\"policy-io-table\" class=\"numbers\"><thead><tr><th>run</th><th>transport</th><th>steps</th><th>p50 µs</th><th>p90 µs</th><th>p99 µs</th><th>p99.9 µs</th><th>max µs</th><th>budget</th><th>deadline misses</th><th>late replies</th><th>invalid actions</th><th>policy failures</th></tr></thead><tbody>";
        for r in io_runs {
            let io = r.policy_io.as_ref().expect("filtered");
            let l = &io.latency;
            let t = io.transport;
            let _ = write!(
                s,
                "<tr><th>{}</th><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                escape(&r.label),
                if t.is_some() { "policy server" } else { "in process" },
                l.count,
                fmt_opt(Some(l.p50_us), 1),
                fmt_opt(Some(l.p90_us), 1),
                fmt_opt(Some(l.p99_us), 1),
                fmt_opt(Some(l.p999_us), 1),
                fmt_opt(Some(l.max_us), 1),
                r.header.io.budget_s.map_or("none".into(), |b| format!("{:.3} ms", b * 1e3)),
                io.deadline_misses,
                t.map_or("–".into(), |t| t.late_replies.to_string()),
                io.invalid_actions,
                t.map_or("–".into(), |t| t.policy_failures.to_string()),
            );
        }
        s += "</tbody></table>";
        if !data.latency.is_empty() {
            s += "<div class=\"grid\">";
            for f in &data.latency {
                s += &figure(f);
            }
            s += "</div>";
        }
        s += "</section>";
    }
    s
}

/// The viewer page for one episode's scene with the bundled `script` inlined.
pub fn view_html(scene: &ViewScene, script: &str) -> String {
    let mut info = String::new();
    for (k, v) in &scene.info {
        let _ = write!(info, "<dt>{}</dt><dd>{}</dd>", escape(k), escape(v));
    }
    fill(
        VIEW_TEMPLATE,
        &[
            ("title", &escape(&scene.title)),
            ("style", VIEW_STYLE),
            ("info", &info),
            (
                "steps_max",
                &(scene.time_s.len().saturating_sub(1)).to_string(),
            ),
            ("data", &inline_json(scene)),
            ("script", script),
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fill_replaces_each_placeholder_once_and_never_inside_inserted_text() {
        let out = fill("a{{x}}b{{y}}c{{z}}", &[("x", "{{y}}"), ("y", "Y")]);
        assert_eq!(out, "a{{y}}bYc{{z}}");
    }

    #[test]
    fn inlined_scripts_and_json_cannot_close_their_element() {
        assert_eq!(inline_script("s='</SCRIPT>';"), "s='<\\/SCRIPT>';");
        let json = inline_json(&serde_json::json!({"a": "</script><b>"}));
        assert!(!json.contains('<'));
        let back: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert_eq!(back["a"], "</script><b>");
    }
}
