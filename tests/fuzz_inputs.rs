//! Property tests of every reader of outside input: the motion importers (TWIST pickle,
//! BeyondMimic npz, LAFAN CSV, force CSV), the dataset reader (manifest and sequence
//! files), the results reader (`run.json`, `episodes.jsonl`, `summary.json`) and the
//! sweep's files (spec TOML, `plan.json`, `done.json`, `failed.json`). Each is fed valid
//! files damaged at random — cut short, bits flipped, bytes inserted or overwritten,
//! containers nested thousands deep, numbers replaced — and must return (an error naming
//! the file, or a value that holds what it claims) within seconds: never a panic, never a
//! hang. The Slurm script of a sweep directory with shell and sbatch syntax in its name
//! is either refused or passes `bash -n` and runs exactly `thorarena sweep task DIR`.
//!
//! `PROPTEST_CASES` sets the cases per reader (default 800 here: 4 000 in all, run by
//! CI). A longer run: `PROPTEST_CASES=50000 cargo test --release --test fuzz_inputs`.

use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;
use thorarena::eval::results::{read_header, read_summary, EpisodeLog};
use thorarena::sim::motion::import::force_csv::read_force_csv;
use thorarena::sim::motion::import::lafan_csv::read_lafan_csv;
use thorarena::sim::motion::import::npz::read_beyondmimic_npz;
use thorarena::sim::motion::import::twist_pkl::read_twist_pkl;
use thorarena::sim::motion::{Dataset, DatasetWriter};
mod prereq;
use thorarena::campaign::sweep::{task_state, Plan, SweepSpec, TaskState};

mod common;
use common::{g1, sample_sequence};

/// Longest a reader may take on one damaged file.
const WATCHDOG: Duration = Duration::from_secs(20);

fn config() -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(800);
    ProptestConfig {
        cases,
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// One damage done to a file; positions are fractions of its length.
#[derive(Debug, Clone)]
enum Damage {
    Truncate(f64),
    FlipBit(f64, u8),
    Insert(f64, Vec<u8>),
    Overwrite(f64, Vec<u8>),
    /// `count` openings then `count` closings inserted: `[[…]]` in JSON, lists appended
    /// into lists or tuples of tuples in a pickle.
    Nest(f64, (&'static [u8], &'static [u8]), usize),
    /// The whole file made the innermost of `count` nested containers: openings before
    /// it (after a pickle's PROTO), closings after it (before a pickle's STOP).
    Wrap((&'static [u8], &'static [u8]), usize),
    /// The n-th run of digits (counting cyclically) replaced by a number: a task index,
    /// a cell, a count that is out of range but still well-formed.
    Number(usize, &'static str),
}

fn damage() -> impl Strategy<Value = Damage> {
    // Anywhere, or near the start, where the structure is (a pickle or npz is mostly
    // array bytes).
    let at = prop_oneof![0.0..1.0f64, 0.0..0.002f64];
    prop_oneof![
        at.clone().prop_map(Damage::Truncate),
        (at.clone(), 0u8..8).prop_map(|(p, b)| Damage::FlipBit(p, b)),
        (at.clone(), prop::collection::vec(any::<u8>(), 1..64))
            .prop_map(|(p, v)| Damage::Insert(p, v)),
        (at.clone(), prop::collection::vec(any::<u8>(), 1..64))
            .prop_map(|(p, v)| Damage::Overwrite(p, v)),
        (
            at,
            prop::sample::select(vec![
                (&b"["[..], &b"]"[..]),
                (&b"{\"a\":"[..], &b"}"[..]),
                (&b"]"[..], &b"a"[..]),
                (&b"(N"[..], &b"t"[..]),
            ]),
            1usize..20_000
        )
            .prop_map(|(p, u, n)| Damage::Nest(p, u, n)),
    ]
}

fn wrap() -> impl Strategy<Value = Damage> {
    (
        prop::sample::select(vec![
            (&b"["[..], &b"]"[..]),
            (&b"{\"a\":"[..], &b"}"[..]),
            (&b"]"[..], &b"a"[..]),
            (&b"("[..], &b"t"[..]),
        ]),
        1usize..20_000,
    )
        .prop_map(|(u, n)| Damage::Wrap(u, n))
}

fn damages() -> impl Strategy<Value = Vec<Damage>> {
    prop_oneof![
        3 => prop::collection::vec(damage(), 1..4),
        1 => wrap().prop_map(|w| vec![w]),
    ]
}

/// Damage for the sweep's JSON records: the usual, or well-formed numbers out of range.
fn sweep_damages() -> impl Strategy<Value = Vec<Damage>> {
    let number = (
        any::<usize>(),
        prop::sample::select(vec![
            "0",
            "1",
            "2",
            "3",
            "7",
            "99999",
            "18446744073709551615",
        ]),
    )
        .prop_map(|(k, v)| Damage::Number(k, v));
    prop_oneof![
        1 => damages(),
        1 => prop::collection::vec(number, 1..4),
    ]
}

fn apply(bytes: &[u8], damages: &[Damage]) -> Vec<u8> {
    let mut b = bytes.to_vec();
    let at = |b: &Vec<u8>, p: f64| ((b.len() as f64) * p) as usize;
    for d in damages {
        match d {
            Damage::Truncate(p) => {
                let n = at(&b, *p);
                b.truncate(n);
            }
            Damage::FlipBit(p, bit) => {
                if !b.is_empty() {
                    let i = at(&b, *p).min(b.len() - 1);
                    b[i] ^= 1 << bit;
                }
            }
            Damage::Insert(p, v) => {
                let i = at(&b, *p);
                b.splice(i..i, v.iter().copied());
            }
            Damage::Overwrite(p, v) => {
                let i = at(&b, *p);
                let end = (i + v.len()).min(b.len());
                b.splice(i..end, v.iter().copied());
            }
            Damage::Nest(p, (open, close), n) => {
                let i = at(&b, *p);
                let mut nest = open.repeat(*n);
                nest.extend(close.repeat(*n));
                b.splice(i..i, nest);
            }
            Damage::Wrap((open, close), n) => {
                let start = if b.first() == Some(&0x80) {
                    2.min(b.len())
                } else {
                    0
                };
                b.splice(start..start, open.repeat(*n));
                let end = if b.last() == Some(&b'.') {
                    b.len() - 1
                } else {
                    b.len()
                };
                b.splice(end..end, close.repeat(*n));
            }
            Damage::Number(k, value) => {
                let mut runs = Vec::new();
                let mut i = 0;
                while i < b.len() {
                    if b[i].is_ascii_digit() {
                        let start = i;
                        while i < b.len() && b[i].is_ascii_digit() {
                            i += 1;
                        }
                        runs.push(start..i);
                    } else {
                        i += 1;
                    }
                }
                if !runs.is_empty() {
                    let r = runs[k % runs.len()].clone();
                    b.splice(r, value.bytes());
                }
            }
        }
    }
    b
}

/// Runs `read` on another thread and fails if it panics or outlasts [`WATCHDOG`].
fn returns_in_time(what: &str, read: impl FnOnce() + Send + 'static) {
    let (tx, rx) = mpsc::channel();
    let reader = std::thread::Builder::new()
        .stack_size(8 << 20) // the main thread's size: a recursion bound must hold there
        .spawn(move || {
            read();
            let _ = tx.send(());
        })
        .expect("spawn reader");
    match rx.recv_timeout(WATCHDOG) {
        Ok(()) => reader.join().expect("reader returned"),
        Err(mpsc::RecvTimeoutError::Disconnected) => {
            panic!("{what}: the reader panicked (see above)")
        }
        Err(mpsc::RecvTimeoutError::Timeout) => panic!("{what}: no answer in {WATCHDOG:?}"),
    }
}

/// Seeds written once per test binary.
struct Seeds {
    _dir: tempfile::TempDir,
    root: PathBuf,
}

fn seeds() -> &'static Seeds {
    static SEEDS: std::sync::OnceLock<Seeds> = std::sync::OnceLock::new();
    SEEDS.get_or_init(|| {
        let dir = tempfile::tempdir().expect("tempdir");
        let root = dir.path().to_path_buf();
        write_seeds(&root);
        Seeds { _dir: dir, root }
    })
}

/// A TWIST2-style motion pickle written by numpy (`python3` of `./test.sh`'s `.venv`), or
/// `None` when that Python has no numpy (the tests of the pickle then count as skipped).
fn numpy_motion_pickle(root: &Path) -> Option<Vec<u8>> {
    const SCRIPT: &str = "import pickle, sys, numpy as np\n\
        k = np.arange(20)[:, None] * 0.01\n\
        rot = np.zeros((20, 4)); rot[:, 3] = 1.0\n\
        d = {'fps': np.float64(30.0), 'root_pos': np.hstack([k, 0 * k, 0.78 + 0 * k]),\n\
             'root_rot': rot, 'dof_pos': np.zeros((20, 29)) + k}\n\
        pickle.dump(d, open(sys.argv[1], 'wb'))\n";
    let path = root.join("numpy-motion.pkl");
    let out = std::process::Command::new("python3")
        .args(["-c", SCRIPT])
        .arg(&path)
        .output();
    match out {
        Ok(o) if o.status.success() => Some(std::fs::read(&path).unwrap()),
        _ => None,
    }
}

/// Whether the motion-pickle seed exists; when not, its tests are recorded as skipped
/// (once) and return.
fn motion_pickle_seed(test: &str) -> bool {
    static SKIPPED: std::sync::Once = std::sync::Once::new();
    let there = seeds().root.join("motion.pkl").is_file();
    if !there {
        SKIPPED.call_once(|| {
            prereq::skip(
                test,
                "without the reference artifacts the motion-pickle seed is written by python3 with numpy, which this python3 lacks (./test.sh installs it into .venv)",
            )
        });
    }
    there
}

fn write_seeds(root: &Path) {
    let robot = g1();
    // A dataset of two sequences (manifest + safetensors), as `data import` writes it.
    let ds = root.join("dataset");
    let mut w = DatasetWriter::create(&ds, &robot).unwrap();
    for id in ["a", "b"] {
        w.add(&sample_sequence(&robot, id)).unwrap();
    }
    w.finish().unwrap();
    // A finished run of that dataset.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(["eval", "--policy", "hold", "--dataset"])
        .arg(&ds)
        .arg("--out")
        .arg(root.join("run"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A sweep over that dataset: its spec, plan and one record of each kind.
    let spec = root.join("sweep.toml");
    std::fs::write(
        &spec,
        format!(
            "datasets = [\"{}\"]\nsettings = [\"force\", \"no-force\"]\nshards = 2\n[[policy]]\npolicy = \"hold\"\n",
            ds.display()
        ),
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(["sweep", "plan"])
        .arg(&spec)
        .arg("--out")
        .arg(root.join("sweep"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for (task, name, json) in [
        (
            0,
            "done.json",
            r#"{"task": 0, "episodes": 2, "wall_s": 1.5}"#,
        ),
        (
            1,
            "failed.json",
            r#"{"task": 1, "reason": "thorarena eval failed (exit status: 1)", "log_tail": ["--- eval.log", "error: x"]}"#,
        ),
    ] {
        let tdir = root.join(format!("sweep/tasks/{task:06}"));
        std::fs::create_dir_all(&tdir).unwrap();
        std::fs::write(tdir.join(name), json).unwrap();
    }
    // A motion pickle: the real TWIST2 walk when the reference artifacts are here, else
    // one numpy pickles with the same keys (numpy arrays, as in real files: a pickle of
    // plain lists is not a motion file, and damaging an invalid seed tests nothing).
    let walk = thorarena::reference_dir().join("twist2/motions/0807_yanjie_walk_001.pkl");
    let pickle = std::fs::read(&walk)
        .ok()
        .or_else(|| numpy_motion_pickle(root));
    if let Some(pickle) = pickle {
        std::fs::write(root.join("motion.pkl"), pickle).unwrap();
    }
    // A BeyondMimic npz (npyz's writer) and the two CSVs.
    write_npz(&root.join("motion.npz"));
    let q0 = robot.default_pose();
    let lafan: String = (0..20)
        .map(|k| {
            let mut row = vec![0.01 * k as f64, 0.0, 0.78, 0.0, 0.0, 0.0, 1.0];
            row.extend(&q0);
            row.iter().map(f64::to_string).collect::<Vec<_>>().join(",") + "\n"
        })
        .collect();
    std::fs::write(root.join("motion.csv"), lafan).unwrap();
    let force: String = std::iter::once("time,fx,fy,fz\n".to_string())
        .chain((0..50).map(|k| format!("{},{},0.5,-1\n", k as f64 * 0.01, k)))
        .collect();
    std::fs::write(root.join("force.csv"), force).unwrap();
}

fn write_npz(path: &Path) {
    use npyz::npz::NpzWriter;
    use npyz::zip::write::FileOptions;
    use npyz::zip::CompressionMethod;
    use npyz::WriterBuilder;
    let (t, b, j) = (10u64, 2u64, 29u64);
    let mut w = NpzWriter::create(path).unwrap();
    let members: [(&str, Vec<u64>); 5] = [
        ("fps", vec![1]),
        ("joint_pos", vec![t, j]),
        ("joint_vel", vec![t, j]),
        ("body_pos_w", vec![t, b, 3]),
        ("body_quat_w", vec![t, b, 4]),
    ];
    for (name, shape) in members {
        let n: u64 = shape.iter().product();
        let data: Vec<f64> = if name == "fps" {
            vec![50.0]
        } else if name == "body_quat_w" {
            (0..n).map(|i| if i % 4 == 0 { 1.0 } else { 0.0 }).collect()
        } else {
            (0..n).map(|i| i as f64 * 1e-3).collect()
        };
        let opts = FileOptions::default().compression_method(CompressionMethod::Stored);
        let mut a = w
            .array::<f64>(name, opts)
            .unwrap()
            .default_dtype()
            .shape(&shape)
            .begin_nd()
            .unwrap();
        a.extend(data).unwrap();
        a.finish().unwrap();
    }
    w.zip_writer().finish().unwrap();
}

/// A copy of seed file `name` with `damages` done, at a fresh path; returns that path.
fn damaged(name: &str, damages: &[Damage]) -> (tempfile::TempDir, PathBuf) {
    let bytes = std::fs::read(seeds().root.join(name)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, apply(&bytes, damages)).unwrap();
    (dir, path)
}

/// A copy of the seed directory `name` with one of its files damaged.
fn damaged_dir(name: &str, file: &str, damages: &[Damage]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join(name);
    copy_dir(&seeds().root.join(name), &copy);
    let bytes = std::fs::read(copy.join(file)).unwrap();
    std::fs::write(copy.join(file), apply(&bytes, damages)).unwrap();
    (dir, copy)
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        let dest = to.join(p.file_name().unwrap());
        if p.is_dir() {
            copy_dir(&p, &dest);
        } else {
            std::fs::copy(&p, &dest).unwrap();
        }
    }
}

/// The first sequence file of the seed dataset, relative to it.
fn first_sequence_file() -> String {
    let ds = seeds().root.join("dataset");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(ds.join("manifest.json")).unwrap()).unwrap();
    manifest["sequences"][0]["file"]
        .as_str()
        .unwrap()
        .to_string()
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn twist_pickles(d in damages()) {
        if !motion_pickle_seed("fuzz_inputs::twist_pickles") {
            return Ok(());
        }
        let (_tmp, path) = damaged("motion.pkl", &d);
        returns_in_time("read_twist_pkl", move || {
            let _ = read_twist_pkl(&path);
        });
    }

    #[test]
    fn beyondmimic_npz(d in damages()) {
        let (_tmp, path) = damaged("motion.npz", &d);
        returns_in_time("read_beyondmimic_npz", move || {
            let _ = read_beyondmimic_npz(&path, None);
        });
    }

    #[test]
    fn lafan_and_force_csv(d in damages()) {
        let (_a, motion) = damaged("motion.csv", &d);
        let (_b, force) = damaged("force.csv", &d);
        returns_in_time("read_lafan_csv / read_force_csv", move || {
            let _ = read_lafan_csv(&motion, 30.0);
            let _ = read_force_csv(&force);
        });
    }

    #[test]
    fn dataset_manifest_and_sequences(d in damages(), manifest in any::<bool>()) {
        let file = if manifest { "manifest.json".to_string() } else { first_sequence_file() };
        let (_tmp, ds) = damaged_dir("dataset", &file, &d);
        returns_in_time("Dataset::open / load_all", move || {
            if let Ok(dataset) = Dataset::open(&ds, &g1()) {
                let _ = dataset.load_all();
            }
        });
    }

    #[test]
    fn results_run_directory(d in damages(), which in 0usize..3) {
        let file = ["run.json", "episodes.jsonl", "summary.json"][which];
        let (_tmp, run) = damaged_dir("run", file, &d);
        returns_in_time("read_header / EpisodeLog::read / read_summary", move || {
            let _ = read_summary(&run);
            if let Ok(header) = read_header(&run) {
                let _ = EpisodeLog::read(&run.join("episodes.jsonl"), &header);
            }
        });
    }

    #[test]
    fn sweep_plan(d in sweep_damages()) {
        let (_tmp, dir) = damaged_dir("sweep", "plan.json", &d);
        returns_in_time("Plan::load", move || {
            if let Ok(plan) = Plan::load(&dir) {
                plan_holds_what_it_claims(&plan);
            }
        });
    }

    #[test]
    fn sweep_task_records(d in sweep_damages(), task in 0usize..2) {
        let file = format!("tasks/{task:06}/{}", ["done.json", "failed.json"][task]);
        let (_tmp, dir) = damaged_dir("sweep", &file, &d);
        returns_in_time("task_state", move || match task_state(&dir, task) {
            Ok(TaskState::Done(r)) => assert_eq!(r.task, task, "done.json of task {task}"),
            Ok(TaskState::Failed(r)) => {
                assert_eq!(r.task, task, "failed.json of task {task}");
            }
            Ok(_) => {}
            Err(e) => assert!(e.to_string().contains(&file), "{e}"),
        });
    }

    #[test]
    fn sweep_spec(d in damages()) {
        let (_tmp, path) = damaged("sweep.toml", &d);
        returns_in_time("SweepSpec::load", move || {
            if let Err(e) = SweepSpec::load(&path) {
                assert!(e.to_string().contains("sweep.toml"), "{e}");
            }
        });
    }
}

/// What a plan that loaded must hold: every task and cell where its index says, every
/// task's cell and shard in range.
fn plan_holds_what_it_claims(plan: &Plan) {
    assert!(!plan.tasks.is_empty() && !plan.cells.is_empty());
    for (i, c) in plan.cells.iter().enumerate() {
        assert_eq!(c.index, i);
    }
    for (i, t) in plan.tasks.iter().enumerate() {
        assert_eq!(t.index, i);
        let cell = plan.cells.get(t.cell).expect("the task's cell exists");
        assert_eq!(t.shard.1, cell.shards);
        assert!(t.shard.0 < t.shard.1);
    }
}

/// Shell syntax that sbatch reads literally (no whitespace, quote, `\\`, `#`): a script
/// for a directory named with it is written, and its body must not run it.
const SHELL_FRAGMENTS: [&str; 16] = [
    "$(touch${IFS}M)",
    "`touch${IFS}M`",
    ";touch${IFS}M;",
    "&&touch${IFS}M",
    "|touch${IFS}M",
    ">M",
    "$((1+1))",
    "${HOME}",
    "$M",
    "*",
    "?",
    "~",
    "!",
    "{session}",
    "%a",
    "%%",
];

/// A sweep directory name: shell syntax, sbatch syntax, control characters, text.
fn hostile_name() -> impl Strategy<Value = String> {
    let refused = prop::sample::select(vec![
        " ",
        "\t",
        "\n",
        "\r",
        "'",
        "\"",
        "#",
        "\\",
        "\u{1b}[31m",
        "\ntouch M\n",
    ]);
    let plain = prop::sample::select(vec![
        "a", "Z9", "-", "--x", ".", "é", "=", ",", "(", ")", "%",
    ]);
    let fragment = prop_oneof![
        3 => prop::sample::select(SHELL_FRAGMENTS.to_vec()),
        2 => plain,
        1 => refused,
    ];
    prop::collection::vec(fragment, 1..6)
        .prop_map(|v| v.concat())
        .prop_filter("a name", |n| n != "." && n != "..")
}

#[test]
fn slurm_scripts_are_written_for_shell_syntax_in_a_directory_name() {
    for name in SHELL_FRAGMENTS {
        assert!(
            slurm_script_is_refused_or_injection_free(&format!("x{name}")),
            "{name:?} was refused: the property would test nothing for it"
        );
    }
}

fn slurm_config() -> ProptestConfig {
    let c = config();
    ProptestConfig {
        cases: c.cases.min(200),
        ..c
    }
}

proptest! {
    #![proptest_config(slurm_config())]

    #[test]
    fn slurm_scripts_of_hostile_directories(name in hostile_name()) {
        let _written = slurm_script_is_refused_or_injection_free(&name);
    }
}

/// Whether a script was written (and then checked).
fn slurm_script_is_refused_or_injection_free(name: &str) -> bool {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join(name);
    std::fs::create_dir_all(dir.join("tasks")).unwrap();
    std::fs::copy(seeds().root.join("sweep/plan.json"), dir.join("plan.json")).unwrap();
    let stub = tmp.path().join("stub");
    std::fs::write(&stub, "#!/bin/sh\nprintf '%s\\0' \"$@\" > \"$ARGS_FILE\"\n").unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&stub, std::fs::Permissions::from_mode(0o755)).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(["sweep", "slurm"])
        .arg(&dir)
        .arg("--thorarena")
        .arg(&stub)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!stderr.contains("panicked"), "{name:?}: {stderr}");
    if !o.status.success() {
        assert!(stderr.contains("sweep directory"), "{name:?}: {stderr}");
        return false;
    }
    let script = dir.join("slurm/sweep.sbatch");
    let text = std::fs::read_to_string(&script).unwrap();
    let syntax = std::process::Command::new("bash")
        .arg("-n")
        .arg(&script)
        .output()
        .unwrap();
    assert!(syntax.status.success(), "{name:?}: bash -n:\n{text}");
    // What sbatch reads: each #SBATCH line one option, the log path the directory's.
    let canonical = std::fs::canonicalize(&dir).unwrap();
    for line in text.lines().filter(|l| l.starts_with("#SBATCH")) {
        let words: Vec<&str> = line["#SBATCH".len()..].split_whitespace().collect();
        assert_eq!(words.len(), 1, "{name:?}: {line:?}");
        assert!(
            !words[0].contains(['#', '"', '\'', '\\']),
            "{name:?}: {line:?}"
        );
        if let Some(log) = words[0].strip_prefix("--output=") {
            let log = log.replace("%%", "\u{0}").replace("%a", "\u{1}");
            assert!(!log.contains('%'), "{name:?}: an unescaped % in {line:?}");
            let log = log.replace('\u{0}', "%").replace('\u{1}', "%a");
            assert_eq!(
                Path::new(&log),
                canonical.join("slurm/logs/task-%a.log"),
                "{name:?}"
            );
        }
    }
    // The body runs exactly `thorarena sweep task DIR` and nothing else.
    let cwd = tmp.path().join("cwd");
    std::fs::create_dir(&cwd).unwrap();
    let args_file = tmp.path().join("args");
    let run = std::process::Command::new("bash")
        .arg(&script)
        .current_dir(&cwd)
        .env("ARGS_FILE", &args_file)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{name:?}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let left: Vec<_> = std::fs::read_dir(&cwd).unwrap().collect();
    assert!(
        left.is_empty(),
        "{name:?}: the script created files:\n{text}"
    );
    let args = std::fs::read(&args_file).unwrap();
    let args: Vec<&[u8]> = args.split(|&b| b == 0).filter(|a| !a.is_empty()).collect();
    use std::os::unix::ffi::OsStrExt;
    assert_eq!(
        args,
        [&b"sweep"[..], b"task", canonical.as_os_str().as_bytes()],
        "{name:?}:\n{text}"
    );
    true
}

#[test]
fn the_seeds_are_valid_so_the_damage_is_what_is_tested() {
    let s = &seeds().root;
    if motion_pickle_seed("fuzz_inputs::twist_pickles") {
        read_twist_pkl(&s.join("motion.pkl")).unwrap();
    }
    read_beyondmimic_npz(&s.join("motion.npz"), None).unwrap();
    read_lafan_csv(&s.join("motion.csv"), 30.0).unwrap();
    read_force_csv(&s.join("force.csv")).unwrap();
    Dataset::open(&s.join("dataset"), &g1())
        .unwrap()
        .load_all()
        .unwrap();
    let header = read_header(&s.join("run")).unwrap();
    assert_eq!(
        EpisodeLog::read(&s.join("run/episodes.jsonl"), &header)
            .unwrap()
            .records
            .len(),
        4
    );
    read_summary(&s.join("run")).unwrap();
    SweepSpec::load(&s.join("sweep.toml")).unwrap();
    let plan = Plan::load(&s.join("sweep")).unwrap();
    assert_eq!(plan.tasks.len(), 4);
    plan_holds_what_it_claims(&plan);
    assert!(matches!(
        task_state(&s.join("sweep"), 0),
        Ok(TaskState::Done(_))
    ));
    assert!(matches!(
        task_state(&s.join("sweep"), 1),
        Ok(TaskState::Failed(_))
    ));
}
