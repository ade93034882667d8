//! lambert-fuzz: coverage-guided mutation fuzzing of every input format
//! (`lambert::inputs::Input`), on stable Rust.
//!
//! cargo-fuzz needs nightly; instead `scripts/fuzz` builds this harness
//! with LLVM's SanitizerCoverage inline 8-bit counters (`-C
//! passes=sancov-module`, which stable rustc accepts), and the harness
//! implements the one callback that needs (`__sanitizer_cov_8bit_counters_init`):
//! an input that raises any counter into a new bucket (1, 2, 3, 4-7, …,
//! 128+ hits, as AFL buckets them) joins the corpus. Built without the
//! flags, it is a plain mutation fuzzer over the saved corpus (the short
//! CI pass).
//!
//! Every input is checked for: a panic; a hang (over one second); an
//! allocation beyond a fixed budget plus a multiple of the input's size
//! (peak live bytes, counted by `lambert::memory::Counting`); and, for a
//! model that parses, a BVH (or its compressed form) that fails
//! `validate`, built from its triangles alone. Each finding is
//! saved under the artifacts folder and the run exits with status 1.
//!
//! lambert-fuzz TARGET|all [--runs N] [--seconds S] [--corpus DIR]…
//!              [--out DIR] [--artifacts DIR] [--seed N]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

use lambert::inputs::Input;

/// The allocation budget of one input: FIXED_BUDGET + SIZE_MULTIPLE × its
/// length. A mesh's parsed form (f64 positions, corner normals, Vec
/// doubling) is a few dozen times its text; see docs/reliability.md.
const FIXED_BUDGET: usize = 64 << 20;
const SIZE_MULTIPLE: usize = 128;
/// An input slower than this is a hang.
const HANG: Duration = Duration::from_secs(1);
/// Past this the watchdog stops the process (the input never returned).
const STUCK: Duration = Duration::from_secs(20);
/// Refused outright, so that a runaway request is a finding and not the
/// machine's OOM killer.
const HARD_CAP: usize = 4 << 30;
/// Mutants are kept below this length.
const MAX_LEN: usize = 64 << 10;

#[global_allocator]
static ALLOCATOR: lambert::memory::Counting = lambert::memory::Counting;

// ---- the input being run, for a fatal finding -----------------------------

/// A copy of the input being run, written out when the process must stop
/// (a hard-cap allocation, a stuck input); its capacity is reserved up front
/// so that copying into it does not allocate.
static CURRENT: Mutex<Vec<u8>> = Mutex::new(Vec::new());
/// Opened before the run: writing it on the way down allocates nothing.
static FATAL_FILE: Mutex<Option<std::fs::File>> = Mutex::new(None);

fn fatal(what: &[u8]) {
    let mut err = std::io::stderr();
    let _ = err.write_all(b"lambert-fuzz: fatal: ");
    let _ = err.write_all(what);
    let _ = err.write_all(b"; the input is saved as fatal-input in the artifacts folder\n");
    let file = FATAL_FILE.try_lock();
    if let (Ok(Some(file)), Ok(input)) = (file.as_ref().map(|f| f.as_ref()), CURRENT.try_lock()) {
        let mut file: &std::fs::File = file;
        let _ = file.set_len(0);
        let _ = file.write_all(&input);
        let _ = file.sync_all();
    }
}

/// Nanoseconds since EPOCH at which the current input began; 0 between inputs.
static STARTED: AtomicU64 = AtomicU64::new(0);
static EPOCH: OnceLock<Instant> = OnceLock::new();

fn now_ns() -> u64 {
    EPOCH.get_or_init(Instant::now).elapsed().as_nanos() as u64 + 1
}

fn watchdog() {
    std::thread::spawn(|| {
        loop {
            std::thread::sleep(Duration::from_millis(250));
            let started = STARTED.load(Relaxed);
            if started != 0 && now_ns() - started > STUCK.as_nanos() as u64 {
                fatal(b"an input ran for over 20 s (a hang)");
                std::process::abort();
            }
        }
    });
}

// ---- coverage ---------------------------------------------------------------

/// Counter regions SanitizerCoverage registered (start, length), deduplicated:
/// every instrumented module's constructor passes the whole linked section.
static REGIONS: Mutex<Vec<(usize, usize)>> = Mutex::new(Vec::new());

/// Called by the constructors SanitizerCoverage adds (inline 8-bit counters).
#[unsafe(no_mangle)]
pub extern "C" fn __sanitizer_cov_8bit_counters_init(start: *mut u8, stop: *mut u8) {
    let mut regions = REGIONS.lock().unwrap_or_else(|e| e.into_inner());
    let region = (start as usize, stop as usize - start as usize);
    if region.1 > 0 && !regions.contains(&region) {
        regions.push(region);
    }
}

struct Coverage {
    regions: Vec<(usize, usize)>,
    /// Per counter, the buckets of hit counts seen so far.
    seen: Vec<u8>,
}

impl Coverage {
    fn new() -> Coverage {
        let regions = REGIONS.lock().unwrap().clone();
        let total = regions.iter().map(|r| r.1).sum();
        Coverage {
            regions,
            seen: vec![0; total],
        }
    }

    fn counters(&self) -> usize {
        self.seen.len()
    }

    fn reset(&self) {
        for &(start, len) in &self.regions {
            // SAFETY: the region is a live counter section that only
            // instrumented code on this thread writes.
            unsafe { std::ptr::write_bytes(start as *mut u8, 0, len) };
        }
    }

    /// Whether the counters since `reset` reached a new bucket anywhere;
    /// records them and zeroes the counters.
    fn collect(&mut self) -> bool {
        let mut new = false;
        let mut offset = 0;
        for &(start, len) in &self.regions {
            // SAFETY: as in `reset`.
            let counters = unsafe { std::slice::from_raw_parts_mut(start as *mut u8, len) };
            let seen = &mut self.seen[offset..offset + len];
            for (words, seen) in counters.chunks_mut(8).zip(seen.chunks_mut(8)) {
                if words.iter().all(|&c| c == 0) {
                    continue;
                }
                for (c, s) in words.iter_mut().zip(seen.iter_mut()) {
                    let bucket = match *c {
                        0 => 0,
                        1 => 1,
                        2 => 2,
                        3 => 4,
                        4..=7 => 8,
                        8..=15 => 16,
                        16..=31 => 32,
                        32..=127 => 64,
                        _ => 128,
                    };
                    if bucket & !*s != 0 {
                        *s |= bucket;
                        new = true;
                    }
                    *c = 0;
                }
            }
            offset += len;
        }
        new
    }
}

// ---- mutation ---------------------------------------------------------------

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        // xorshift64*
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Numbers at the edges of what parsers handle.
const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "3",
    "255",
    "256",
    "65535",
    "65536",
    "2147483647",
    "-2147483648",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "1e308",
    "1e309",
    "-1e308",
    "1e-320",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1.5",
    "0x10",
    "999999999999999999999",
    "1e18",
    "1e-18",
];

/// Tokens of each format, for insertion.
fn dictionary(input: Input) -> &'static [&'static str] {
    match input {
        Input::Toml => &[
            "[camera]",
            "[render]",
            "[[spheres]]",
            "[[triangles]]",
            "[[meshes]]",
            "[[lights]]",
            "position",
            "look_at",
            "up",
            "fov",
            "resolution",
            "spp",
            "seed",
            "shadows",
            "background",
            "ambient",
            "intersect",
            "center",
            "radius",
            "albedo",
            "v0",
            "v1",
            "v2",
            "path",
            "normals",
            "translate",
            "scale",
            "rotate",
            "kind",
            "direction",
            "irradiance",
            "intensity",
            " = ",
            "[0, 0, 0]",
            "[1e30, 1, 1]",
            "\"\"",
            "true",
            "\"smooth\"",
            "\"point\"",
            "\"directional\"",
            "\n",
        ],
        Input::Obj => &[
            "v ", "vn ", "vt ", "f ", "o ", "g ", "s ", "l ", "p ", "usemtl ", "mtllib ", "1/1/1",
            "1//1", "-1", "-2", "/", "//", "\n", "\r\n", "#", "\\\n", "\u{feff}",
        ],
        Input::Mtl => &[
            "newmtl ", "Kd ", "Ka ", "Ks ", "map_Kd ", "\n", "#", "\u{feff}",
        ],
        Input::Ply => &[
            "ply\n",
            "format ascii 1.0\n",
            "format binary_little_endian 1.0\n",
            "format binary_big_endian 1.0\n",
            "element vertex ",
            "element face ",
            "property float x\n",
            "property double y\n",
            "property uchar z\n",
            "property list uchar int vertex_indices\n",
            "property list uint uint vertex_index\n",
            "property float nx\n",
            "comment ",
            "end_header\n",
            "\n",
            "\r\n",
            " ",
        ],
        Input::Gltf => &[
            "\"asset\"",
            "\"version\"",
            "\"2.0\"",
            "\"scene\"",
            "\"scenes\"",
            "\"nodes\"",
            "\"meshes\"",
            "\"primitives\"",
            "\"attributes\"",
            "\"POSITION\"",
            "\"NORMAL\"",
            "\"indices\"",
            "\"accessors\"",
            "\"bufferViews\"",
            "\"buffers\"",
            "\"byteLength\"",
            "\"byteOffset\"",
            "\"byteStride\"",
            "\"count\"",
            "\"componentType\"",
            "5126",
            "5125",
            "5123",
            "5121",
            "\"type\"",
            "\"VEC3\"",
            "\"SCALAR\"",
            "\"mode\"",
            "\"children\"",
            "\"matrix\"",
            "\"translation\"",
            "\"scale\"",
            "\"rotation\"",
            "\"camera\"",
            "\"cameras\"",
            "\"perspective\"",
            "\"extensionsRequired\"",
            "\"KHR_lights_punctual\"",
            "\"uri\"",
            "\"data:application/octet-stream;base64,\"",
            "\"materials\"",
            "\"material\"",
            "\"baseColorFactor\"",
            "glTF",
            "JSON",
            "BIN\0",
            "[",
            "]",
            "{",
            "}",
            ",",
            ":",
        ],
        Input::Stl => &[
            "solid ",
            "endsolid",
            "facet normal 0 0 1\n",
            "outer loop\n",
            "vertex 0 0 0\n",
            "vertex ",
            "endloop\n",
            "endfacet\n",
            "\n",
            "\r\n",
            " ",
            "\0\0\0\0",
        ],
        Input::Rays | Input::Points | Input::Part | Input::Environment => &[],
    }
}

/// Little-endian values at the edges of what binary fields hold.
const WORDS: &[u32] = &[
    0,
    1,
    2,
    0x7f,
    0x80,
    0xff,
    0x100,
    0xffff,
    0x10000,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_ffff,
    0x7f80_0000,
    0xff80_0000,
    0x7fc0_0000,
    0x3f80_0000,
    0x0000_0001,
    0x0080_0000,
];

fn mutate(rng: &mut Rng, parent: &[u8], corpus: &[Vec<u8>], input: Input) -> Vec<u8> {
    let mut data = parent.to_vec();
    let dictionary = dictionary(input);
    let rounds = 1 + rng.below(4);
    for _ in 0..rounds {
        let len = data.len();
        let at = rng.below(len + 1);
        match rng.below(11) {
            0 if len > 0 => {
                let i = rng.below(len);
                data[i] ^= 1 << rng.below(8);
            }
            1 if len > 0 => {
                let i = rng.below(len);
                data[i] = rng.next() as u8;
            }
            2 if len > 0 => {
                let n = 1 + rng.below(16.min(len - at.min(len - 1)));
                let at = at.min(len - 1);
                data.drain(at..(at + n).min(len));
            }
            3 if len > 0 => {
                // Repeat a chunk: counts and lists grow.
                let start = rng.below(len);
                let n = 1 + rng.below((len - start).min(64));
                let chunk = data[start..start + n].to_vec();
                let times = 1 + rng.below(4);
                for _ in 0..times {
                    data.splice(at..at, chunk.iter().copied());
                }
            }
            4 if !dictionary.is_empty() => {
                let token = dictionary[rng.below(dictionary.len())];
                data.splice(at..at, token.bytes());
            }
            5 => {
                // Replace the number under `at` (or insert one).
                let number = NUMBERS[rng.below(NUMBERS.len())];
                let is_num = |b: u8| b.is_ascii_digit() || b"+-.eE".contains(&b);
                let mut start = at.min(len);
                while start > 0 && is_num(data[start - 1]) {
                    start -= 1;
                }
                let mut end = at.min(len);
                while end < len && is_num(data[end]) {
                    end += 1;
                }
                data.splice(start..end, number.bytes());
            }
            6 if len >= 4 => {
                let i = rng.below(len - 3);
                let word = WORDS[rng.below(WORDS.len())];
                let word = if rng.below(2) == 0 {
                    word
                } else {
                    word.swap_bytes()
                };
                data[i..i + 4].copy_from_slice(&word.to_le_bytes());
            }
            7 if !corpus.is_empty() => {
                // Splice: our head, another entry's tail.
                let other = &corpus[rng.below(corpus.len())];
                let from = rng.below(other.len() + 1);
                data.truncate(at);
                data.extend_from_slice(&other[from..]);
            }
            8 if len > 0 => data.truncate(at),
            9 if len > 0 => {
                let i = rng.below(len);
                let delta = [1u8, 255, 16, 240][rng.below(4)];
                data[i] = data[i].wrapping_add(delta);
            }
            _ => {
                let n = 1 + rng.below(8);
                let bytes: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
                data.splice(at..at, bytes);
            }
        }
    }
    data.truncate(MAX_LEN);
    data
}

// ---- running inputs ---------------------------------------------------------

static LAST_PANIC: Mutex<Option<String>> = Mutex::new(None);
static QUIET_PANICS: AtomicBool = AtomicBool::new(true);

enum Finding {
    Panic(String),
    Hang(Duration),
    Memory(usize),
    /// A model that parses and whose BVH fails `validate`.
    InvalidTree(String),
}

/// What is wrong with the BVH, and its compressed form, built from a model
/// input that parses (a scene of its triangles); None where they are valid
/// or the input is no model a scene is made of.
fn invalid_tree(input: Input, data: &[u8], path: &Path) -> Option<String> {
    let scene = input.model_scene(data, path).ok()??;
    let bvh = scene.bvh();
    let invalid = bvh
        .validate(scene.triangles(), scene.spheres())
        .err()
        .or_else(|| lambert::cwbvh::validate(&lambert::cwbvh::compress(bvh), bvh).err())?;
    Some(invalid.to_string())
}

struct Outcome {
    finding: Option<Finding>,
    elapsed: Duration,
    /// Peak bytes allocated beyond what was live before the input.
    allocated: usize,
}

fn run_one(input: Input, data: &[u8], path: &Path) -> Outcome {
    {
        let mut current = CURRENT.lock().unwrap();
        current.clear();
        current.extend_from_slice(data);
    }
    let base = lambert::memory::reset_peak();
    let start = Instant::now();
    STARTED.store(now_ns(), Relaxed);
    let result = std::panic::catch_unwind(|| {
        input.parse(data, path).map(|()| invalid_tree(input, data, path))
    });
    STARTED.store(0, Relaxed);
    let elapsed = start.elapsed();
    let allocated = lambert::memory::peak().saturating_sub(base);
    let budget = FIXED_BUDGET + SIZE_MULTIPLE * data.len();
    let finding = match result {
        Err(_) => Some(Finding::Panic(
            LAST_PANIC
                .lock()
                .unwrap()
                .take()
                .unwrap_or_else(|| "a panic".into()),
        )),
        Ok(_) if elapsed > HANG => Some(Finding::Hang(elapsed)),
        Ok(_) if allocated > budget => Some(Finding::Memory(allocated)),
        Ok(Ok(Some(invalid))) => Some(Finding::InvalidTree(invalid)),
        Ok(_) => None,
    };
    Outcome {
        finding,
        elapsed,
        allocated,
    }
}

fn fnv(data: &[u8]) -> u64 {
    data.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    })
}

struct Options {
    targets: Vec<Input>,
    runs: Option<u64>,
    seconds: Option<f64>,
    corpora: Vec<PathBuf>,
    out: Option<PathBuf>,
    artifacts: PathBuf,
    seed: u64,
}

#[derive(Default)]
struct Report {
    runs: u64,
    corpus: usize,
    findings: usize,
    slowest: Duration,
    most_allocated: usize,
    /// The largest (allocated − FIXED_BUDGET) / length over inputs that
    /// allocated more than the fixed budget.
    worst_ratio: f64,
}

fn read_corpus(dirs: &[PathBuf], input: Input) -> Vec<Vec<u8>> {
    let mut files: Vec<PathBuf> = Vec::new();
    for dir in dirs {
        // A corpus folder per target, or one folder holding several.
        for d in [dir.join(input.name()), dir.clone()] {
            if let Ok(entries) = std::fs::read_dir(&d) {
                for entry in entries.flatten() {
                    let path = entry.path();
                    if path.is_file() {
                        files.push(path);
                    }
                }
            }
        }
    }
    files.sort();
    files.dedup();
    files
        .iter()
        .filter_map(|f| std::fs::read(f).ok())
        .filter(|d| d.len() <= MAX_LEN)
        .collect()
}

fn fuzz(input: Input, options: &Options, coverage: &mut Coverage) -> Report {
    let mut rng = Rng(options.seed ^ fnv(input.name().as_bytes()) | 1);
    let path = PathBuf::from(format!(
        "/nonexistent/lambert-fuzz/input.{}",
        input.extension()
    ));
    let artifacts = options.artifacts.join(input.name());
    std::fs::create_dir_all(&artifacts).expect("creating the artifacts folder");
    *FATAL_FILE.lock().unwrap() =
        Some(std::fs::File::create(artifacts.join("fatal-input")).expect("creating fatal-input"));
    let out = options.out.as_ref().map(|o| o.join(input.name()));
    if let Some(out) = &out {
        std::fs::create_dir_all(out).expect("creating the corpus output folder");
    }
    let mut corpus = read_corpus(&options.corpora, input);
    if corpus.is_empty() {
        corpus.push(Vec::new());
    }
    let mut report = Report::default();
    let started = Instant::now();
    let mut sites: std::collections::HashMap<String, usize> = Default::default();
    let mut record = |data: &[u8], outcome: &Outcome, report: &mut Report| {
        report.runs += 1;
        report.slowest = report.slowest.max(outcome.elapsed);
        report.most_allocated = report.most_allocated.max(outcome.allocated);
        if outcome.allocated > FIXED_BUDGET && !data.is_empty() {
            let ratio = (outcome.allocated - FIXED_BUDGET) as f64 / data.len() as f64;
            report.worst_ratio = report.worst_ratio.max(ratio);
        }
        let Some(finding) = &outcome.finding else {
            return;
        };
        report.findings += 1;
        let (kind, what) = match finding {
            Finding::Panic(m) => ("crash", format!("panicked: {m}")),
            Finding::Hang(t) => ("hang", format!("took {:.2} s", t.as_secs_f64())),
            Finding::InvalidTree(m) => ("tree", format!("an invalid tree: {m}")),
            Finding::Memory(b) => (
                "memory",
                format!(
                    "allocated {b} bytes, over the budget of {} bytes",
                    FIXED_BUDGET + SIZE_MULTIPLE * data.len()
                ),
            ),
        };
        // One report (and at most three saved inputs) per panic site or
        // kind: a shallow bug is otherwise found thousands of times.
        let site = match finding {
            Finding::Panic(m) => m.lines().next().unwrap_or("").to_string(),
            _ => kind.to_string(),
        };
        let count = sites.entry(site).or_insert(0usize);
        *count += 1;
        if *count > 3 {
            return;
        }
        let file = artifacts.join(format!("{kind}-{:016x}", fnv(data)));
        let _ = std::fs::write(&file, data);
        eprintln!(
            "lambert-fuzz {}: {what}; input saved as {}",
            input.name(),
            file.display()
        );
    };
    // The corpus first, as it is: the replay every pass begins with.
    coverage.reset();
    let seeds = std::mem::take(&mut corpus);
    for data in seeds {
        let outcome = run_one(input, &data, &path);
        coverage.collect();
        record(&data, &outcome, &mut report);
        corpus.push(data);
    }
    let done = |report: &Report| {
        options.runs.is_some_and(|n| report.runs >= n)
            || options
                .seconds
                .is_some_and(|s| started.elapsed().as_secs_f64() >= s)
    };
    while !done(&report) {
        let parent = &corpus[rng.below(corpus.len())];
        let data = mutate(&mut rng, parent, &corpus, input);
        coverage.reset();
        let outcome = run_one(input, &data, &path);
        let new = coverage.collect();
        record(&data, &outcome, &mut report);
        if new {
            if let Some(out) = &out {
                let _ = std::fs::write(out.join(format!("{:016x}", fnv(&data))), &data);
            }
            corpus.push(data);
        }
        if report.runs % 1_000_000 == 0 {
            eprintln!(
                "lambert-fuzz {}: {} inputs, corpus {}, {:.0} inputs/s",
                input.name(),
                report.runs,
                corpus.len(),
                report.runs as f64 / started.elapsed().as_secs_f64()
            );
        }
    }
    report.corpus = corpus.len();
    report
}

fn parse_options() -> Result<Options, String> {
    let mut args = std::env::args().skip(1);
    let target = args
        .next()
        .ok_or("usage: lambert-fuzz TARGET|all [options]")?;
    let targets = if target == "all" {
        Input::ALL.to_vec()
    } else {
        let names: Vec<&str> = Input::ALL.iter().map(|i| i.name()).collect();
        vec![Input::from_name(&target).ok_or(format!(
            "unknown target {target}; the targets are {} (or all)",
            names.join(", ")
        ))?]
    };
    let mut options = Options {
        targets,
        runs: None,
        seconds: None,
        corpora: Vec::new(),
        out: None,
        artifacts: PathBuf::from("fuzz/artifacts"),
        seed: 0x5eed,
    };
    while let Some(flag) = args.next() {
        let mut value = || args.next().ok_or(format!("{flag} needs a value"));
        let number = |v: String| {
            v.parse::<f64>()
                .map_err(|_| format!("{flag} {v}: not a number"))
        };
        match flag.as_str() {
            "--runs" => options.runs = Some(number(value()?)? as u64),
            "--seconds" => options.seconds = Some(number(value()?)?),
            "--corpus" => options.corpora.push(value()?.into()),
            "--out" => options.out = Some(value()?.into()),
            "--artifacts" => options.artifacts = value()?.into(),
            "--seed" => options.seed = number(value()?)? as u64,
            _ => return Err(format!("unknown option {flag}")),
        }
    }
    if options.runs.is_none() && options.seconds.is_none() {
        return Err("give --runs N or --seconds S".into());
    }
    Ok(options)
}

fn main() {
    let options = match parse_options() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("lambert-fuzz: {e}");
            std::process::exit(2);
        }
    };
    CURRENT.lock().unwrap().reserve(MAX_LEN.max(1 << 20));
    lambert::memory::set_cap(HARD_CAP, || {
        fatal(b"an allocation beyond the 4 GiB hard cap")
    });
    std::panic::set_hook(Box::new(|info| {
        if !QUIET_PANICS.load(Relaxed) {
            eprintln!("{info}");
        }
        *LAST_PANIC.lock().unwrap() = Some(info.to_string());
    }));
    watchdog();
    let mut coverage = Coverage::new();
    eprintln!(
        "lambert-fuzz: {} coverage counters{}",
        coverage.counters(),
        if coverage.counters() == 0 {
            " (not instrumented: plain mutation)"
        } else {
            ""
        }
    );
    let mut findings = 0;
    println!(
        "target  inputs  corpus  findings  slowest_ms  peak_alloc_bytes  worst_bytes_per_input_byte"
    );
    for &input in &options.targets {
        let r = fuzz(input, &options, &mut coverage);
        findings += r.findings;
        println!(
            "{:<6}  {}  {}  {}  {:.1}  {}  {:.1}",
            input.name(),
            r.runs,
            r.corpus,
            r.findings,
            r.slowest.as_secs_f64() * 1e3,
            r.most_allocated,
            r.worst_ratio
        );
    }
    std::process::exit(if findings > 0 { 1 } else { 0 });
}
