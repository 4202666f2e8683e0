//! The report's figures as data and as SVG files: each policy has one colour in every
//! figure, legends map colour → policy, marker → setting and dash → sweep axis value, the
//! scatter spreads episodes of equal survival, and every SVG is well-formed XML (parsed by
//! quick-xml) with one `series` group — one polygon or polyline — per dataset, the legend's
//! texts, fonts of 11 pt or more and escaped names. A report's files go into
//! `<stem>-figures/` and never into its own input.

use quick_xml::events::Event;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use thorarena::eval::metrics::EpisodeSeries;
use thorarena::eval::EpisodeRecord;
use thorarena::report::{
    load_runs, report_figures, svg_figures, write_comparison_report, ComparisonFiles, CurveSeries,
    FigureKind, ReportFigures, Swatch, SweepChart, MARKERS, SURVIVAL_JITTER,
};

#[path = "common/run_dir.rs"]
mod run_dir;
/// A policy name that must be escaped in XML.
const ODD: &str = "a<&b\"'>";

/// A run of `policy`: two tasks × two sequences × (force, no-force), every episode whole
/// (survival 1.0) except push_chair's, which fall after `fall` of 30 steps.
fn write_run(dir: &Path, policy: &str, err_m: f64, fall: usize) {
    let header = run_dir::header(policy);
    let force = |k: usize| [0.0, 10.0, 20.0][k % 3];
    let mut records = Vec::new();
    for setting in ["force", "no-force"] {
        for seq in &header.sequences {
            let steps = if seq.task == "push_chair" { fall } else { 30 };
            records.push(EpisodeRecord {
                task: seq.task.clone(),
                sequence_id: seq.sequence_id.clone(),
                setting: setting.into(),
                coefficient: if setting == "force" { 1.0 } else { 0.0 },
                policy: policy.into(),
                termination: (steps < 30).then_some(thorarena::eval::Termination::TorsoTilt),
                faults: Default::default(),
                series: EpisodeSeries {
                    kp_err_m: (0..steps)
                        .map(|k| err_m * (1.0 + force(k) / 20.0))
                        .collect(),
                    kp_err_upper_m: vec![err_m; steps],
                    kp_err_lower_m: vec![err_m; steps],
                    total_force_n: (0..steps).map(force).collect(),
                    power_w: vec![100.0; steps],
                    root_drift_m: vec![0.01; steps],
                    kp_err_global_m: Vec::new(),
                    steps_ref: 30,
                },
            });
        }
    }
    run_dir::write_run(dir, &header, &records, true);
}

/// Three runs: the odd-named policy, and `hold` twice (a second run of one policy).
fn three_runs(dir: &Path) -> Vec<PathBuf> {
    let dirs = ["odd", "hold-1", "hold-2"].map(|d| dir.join(d)).to_vec();
    write_run(&dirs[0], ODD, 0.02, 12);
    write_run(&dirs[1], "hold", 0.05, 20);
    write_run(&dirs[2], "hold", 0.04, 25);
    dirs
}

/// A sweep chart: both policies at two force coefficients under two latency rules.
fn sweep_chart() -> SweepChart {
    let mut series = Vec::new();
    for policy in [ODD, "hold"] {
        for (variant, y) in [("lock-step", 80.0), ("5ms", 70.0)] {
            series.push(CurveSeries {
                label: format!("{policy} · {variant}"),
                policy: policy.into(),
                variant: variant.into(),
                points: vec![[0.0, y], [1.0, y - 20.0]],
            });
        }
    }
    SweepChart {
        id: "sweep-fats-vs-coefficient".into(),
        title: "FATS against the force replay coefficient".into(),
        x_label: "force replay coefficient".into(),
        y_label: "FATS".into(),
        series,
    }
}

fn figures() -> (tempfile::TempDir, ReportFigures) {
    let tmp = tempfile::tempdir().unwrap();
    let runs = load_runs(&three_runs(tmp.path())).unwrap();
    let figures = report_figures(&runs, &[sweep_chart()]);
    (tmp, figures)
}

/// An element of a parsed SVG.
#[derive(Debug, Default)]
struct Element {
    name: String,
    attrs: BTreeMap<String, String>,
    text: String,
    children: Vec<Element>,
}

impl Element {
    fn attr(&self, key: &str) -> Option<&str> {
        self.attrs.get(key).map(String::as_str)
    }

    fn descendants(&self) -> Vec<&Element> {
        let mut out = Vec::new();
        for c in &self.children {
            out.push(c);
            out.extend(c.descendants());
        }
        out
    }
}

/// Parses a whole XML document with quick-xml; any malformation is a panic naming it.
fn parse(xml: &str) -> Element {
    let mut reader = quick_xml::Reader::from_str(xml);
    let mut stack = vec![Element::default()];
    let element = |e: &quick_xml::events::BytesStart| Element {
        name: String::from_utf8(e.name().as_ref().to_vec()).unwrap(),
        attrs: e
            .attributes()
            .map(|a| {
                let a = a.expect("well-formed attribute");
                (
                    String::from_utf8(a.key.as_ref().to_vec()).unwrap(),
                    a.unescape_value().expect("escaped attribute").into_owned(),
                )
            })
            .collect(),
        ..Default::default()
    };
    loop {
        match reader
            .read_event()
            .unwrap_or_else(|e| panic!("not XML: {e}\n{xml}"))
        {
            Event::Start(e) => stack.push(element(&e)),
            Event::Empty(e) => stack.last_mut().unwrap().children.push(element(&e)),
            Event::End(_) => {
                let done = stack.pop().unwrap();
                stack.last_mut().unwrap().children.push(done);
            }
            Event::Text(t) => stack.last_mut().unwrap().text += &t.decode().unwrap(),
            Event::GeneralRef(r) => {
                let c = match r.resolve_char_ref().expect("a valid reference") {
                    Some(c) => c,
                    None => match &*r.decode().unwrap() {
                        "amp" => '&',
                        "lt" => '<',
                        "gt" => '>',
                        "quot" => '"',
                        "apos" => '\'',
                        other => panic!("unknown entity &{other};"),
                    },
                };
                stack.last_mut().unwrap().text.push(c);
            }
            Event::Eof => break,
            _ => {}
        }
    }
    assert_eq!(stack.len(), 1, "unclosed elements");
    let mut root = stack.pop().unwrap();
    assert_eq!(root.children.len(), 1, "one root element");
    root.children.pop().unwrap()
}

#[test]
fn every_svg_is_xml_with_a_series_per_dataset_its_legend_and_readable_fonts() {
    let (_tmp, figures) = figures();
    let svgs = svg_figures(&figures);
    assert_eq!(svgs.len(), figures.all().count());
    let ids: BTreeSet<&str> = svgs.iter().map(|s| s.id.as_str()).collect();
    for id in [
        "sweep-fats-vs-coefficient",
        "radar-force",
        "radar-no-force",
        "scatter-tracking-survival",
        "kp-regimes-force",
        "latency-percentiles",
        "latency-faults",
    ] {
        assert!(ids.contains(id), "no figure {id}: {ids:?}");
    }
    for (svg, figure) in svgs.iter().zip(figures.all()) {
        let id = &figure.id;
        assert!(!svg.svg.contains(ODD), "{id}: a name written unescaped");
        let root = parse(&svg.svg);
        assert_eq!(root.name, "svg", "{id}");
        assert!(
            root.attr("width").unwrap().ends_with("pt"),
            "{id}: sized in points"
        );
        let all = root.descendants();
        let series: Vec<&&Element> = all
            .iter()
            .filter(|e| e.name == "g" && e.attr("class") == Some("series"))
            .collect();
        assert_eq!(
            series.len(),
            figure.datasets.len(),
            "{id}: a group per dataset"
        );
        for (g, d) in series.iter().zip(&figure.datasets) {
            assert_eq!(g.attr("data-policy"), Some(d.policy.as_str()), "{id}");
            let shape = match figure.kind {
                FigureKind::Radar => Some("polygon"),
                FigureKind::Lines => Some("polyline"),
                _ => None,
            };
            if let Some(shape) = shape {
                let n = g.children.iter().filter(|c| c.name == shape).count();
                assert_eq!(n, 1, "{id}: one {shape} per series");
            }
            let marks = g.descendants();
            assert!(
                marks
                    .iter()
                    .all(|m| [None, Some(d.color)].contains(&m.attr("stroke"))),
                "{id}: a series drawn in another colour than its policy's"
            );
        }
        let legend: Vec<&str> = all
            .iter()
            .filter(|e| e.attr("class") == Some("legend"))
            .map(|e| e.text.as_str())
            .collect();
        let want: Vec<&str> = figure.legend.iter().map(|e| e.text.as_str()).collect();
        assert_eq!(legend, want, "{id}: the legend's texts, unescaped");
        for d in &figure.datasets {
            assert!(
                legend.iter().any(|t| t.contains(&d.policy)),
                "{id}: the legend does not name {}",
                d.policy
            );
        }
        for t in all.iter().filter(|e| e.name == "text") {
            let size: f64 = t.attr("font-size").unwrap().parse().unwrap();
            assert!(size >= 11.0, "{id}: text {:?} at {size} pt", t.text);
        }
        let title = all.iter().find(|e| e.name == "title").unwrap();
        assert_eq!(title.text, figure.title, "{id}");
    }
}

#[test]
fn each_policy_has_one_colour_across_all_figures_and_the_legends_say_which() {
    let (_tmp, figures) = figures();
    let mut colours: BTreeMap<&str, BTreeSet<&str>> = BTreeMap::new();
    for f in figures.all() {
        for d in &f.datasets {
            colours.entry(&d.policy).or_default().insert(d.color);
            assert!(
                f.legend
                    .iter()
                    .any(|e| e.text.contains(&d.policy) && e.color == d.color),
                "{}: no legend entry for {} in {}",
                f.id,
                d.policy,
                d.color
            );
        }
    }
    assert_eq!(colours.len(), 2, "{colours:?}");
    assert!(colours.values().all(|c| c.len() == 1), "{colours:?}");
    assert_ne!(colours[ODD], colours["hold"]);
    // The second run of `hold` is told apart by dash on a radar, by a hollow marker in
    // the scatter; sweep lines by dash per latency rule, named in the legend.
    let radar = figures
        .radars
        .iter()
        .find(|f| f.id == "radar-force")
        .unwrap();
    let dashes: Vec<usize> = radar.datasets.iter().map(|d| d.dash).collect();
    assert_eq!(dashes, [0, 0, 1]);
    let sweep = &figures.sweep[0];
    for (variant, dash) in [("5ms", 0), ("lock-step", 1)] {
        assert!(sweep
            .legend
            .iter()
            .any(|e| e.text == variant && e.swatch == Swatch::Line { dash }));
        assert!(sweep
            .datasets
            .iter()
            .filter(|d| d.label.ends_with(variant))
            .all(|d| d.dash == dash));
    }
    assert!(sweep
        .caption
        .contains("colour: policy, line style: solid 5ms, dashed lock-step"));
}

#[test]
fn the_scatter_keys_markers_to_settings_and_spreads_equal_survival() {
    let (_tmp, figures) = figures();
    let s = &figures.scatter;
    for (m, setting) in ["force", "no-force"].iter().enumerate() {
        assert!(
            s.legend
                .iter()
                .any(|e| e.text == format!("setting {setting}")
                    && e.swatch
                        == Swatch::Marker {
                            marker: m,
                            filled: true
                        }),
            "{:?}",
            s.legend
        );
        assert!(s
            .datasets
            .iter()
            .filter(|d| d.label.ends_with(&format!(" — {setting}")))
            .all(|d| d.marker == m && MARKERS[d.marker] == MARKERS[m]));
    }
    // clean_table episodes survive whole: 2 sequences × 2 settings × 3 runs at 1.0.
    let whole: Vec<f64> = s
        .datasets
        .iter()
        .flat_map(|d| d.points.iter().zip(&d.episodes))
        .filter(|(_, &e)| figures.episodes[e].survival == 1.0)
        .map(|(p, _)| p[0])
        .collect();
    assert_eq!(whole.len(), 12);
    assert!(whole.iter().all(|x| (x - 1.0).abs() <= SURVIVAL_JITTER));
    let distinct: BTreeSet<u64> = whole.iter().map(|x| x.to_bits()).collect();
    assert!(
        distinct.len() >= 4,
        "equal survival drawn on one spot: {whole:?}"
    );
    // The same episode lands on the same spot every time.
    let (_tmp2, again) = self::figures();
    assert_eq!(again.scatter.datasets[0].points, s.datasets[0].points);
    assert!(s.caption.contains("jittered") && s.caption.contains("marker: setting"));
    assert!(s.legend.iter().any(|e| e.text == "hollow: hold (hold-2)"));
}

#[test]
fn report_writes_an_svg_per_figure_beside_the_page_and_never_into_its_input() {
    let tmp = tempfile::tempdir().unwrap();
    let dirs = three_runs(tmp.path());
    // What `thorarena report RUNS --out OUT [--overwrite]` writes, with a stand-in bundle.
    let report = |runs: &[PathBuf], out: &Path, overwrite: bool| {
        let loaded = load_runs(runs).unwrap();
        let files = ComparisonFiles::beside(out);
        write_comparison_report(&loaded, &files, "/* bundle */", overwrite, runs)
            .map(|written| (files, written))
    };
    let (files, written) = report(&dirs, &tmp.path().join("paper/cmp.html"), false).unwrap();
    let figures = tmp.path().join("paper/cmp-figures");
    assert_eq!(files.figures_dir, figures);
    let on_disk: BTreeSet<String> = std::fs::read_dir(&figures)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(on_disk, written.figures.iter().cloned().collect());
    assert!(on_disk.contains("radar-force.svg") && on_disk.contains("latency-faults.svg"));
    for f in &on_disk {
        parse(&std::fs::read_to_string(figures.join(f)).unwrap());
    }

    // A run directory named like the figures directory of the page: refused even with
    // --overwrite, and nothing written into it.
    let run = tmp.path().join("x-figures");
    std::fs::rename(&dirs[1], &run).unwrap();
    let before: Vec<_> = std::fs::read_dir(&run).unwrap().collect();
    let refused = report(std::slice::from_ref(&run), &tmp.path().join("x.html"), true)
        .unwrap_err()
        .to_string();
    assert!(
        refused.contains("figures directory") && refused.contains("input"),
        "{refused}"
    );
    assert_eq!(std::fs::read_dir(&run).unwrap().count(), before.len());
    assert!(!tmp.path().join("x.html").exists(), "nothing written");
}
