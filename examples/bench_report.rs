//! Writes the benchmarks' table (by default `docs/results/benchmarks` + `.md`) from criterion's
//! results.
//!
//! Criterion keeps each benchmark's last run under `target/criterion/<id>/new/`
//! (`benchmark.json`: its group and name; `estimates.json`: the mean and its 95 % confidence
//! interval). This report gathers them into one table per benchmark file, with the file's
//! module doc above it and the machine stated once at the top.
//!
//! ```sh
//! cargo bench --no-default-features --bench recon     # any benches, as many as wanted
//! cargo run --no-default-features --example bench_report   # writes the table
//! cargo run --no-default-features --example bench_report -- --criterion DIR --out FILE
//! cargo run --no-default-features --example bench_report -- --flags "-- --measurement-time 2"
//! ```

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use serde::Deserialize;

/// `benchmark.json`: which benchmark a result belongs to.
#[derive(Deserialize)]
struct BenchmarkId {
    group_id: String,
    function_id: Option<String>,
    value_str: Option<String>,
    throughput: Option<Throughput>,
}

/// Criterion's throughput, per iteration.
#[derive(Deserialize)]
enum Throughput {
    Bytes(u64),
    BytesDecimal(u64),
    Elements(u64),
    #[serde(other)]
    Other,
}

/// `estimates.json`: the statistics of the last run, in nanoseconds.
#[derive(Deserialize)]
struct Estimates {
    mean: Estimate,
}

#[derive(Deserialize)]
struct Estimate {
    point_estimate: f64,
    confidence_interval: Interval,
}

#[derive(Deserialize)]
struct Interval {
    lower_bound: f64,
    upper_bound: f64,
}

/// One benchmark's row.
struct Row {
    group: String,
    name: String,
    mean_ns: f64,
    low_ns: f64,
    high_ns: f64,
    throughput: Option<Throughput>,
}

/// A benchmark file: its module doc and the groups it declares.
struct BenchFile {
    name: String,
    doc: String,
    groups: Vec<String>,
}

fn main() -> ExitCode {
    let mut criterion = PathBuf::from("target/criterion");
    let mut out = PathBuf::from("docs/results/benchmarks.md");
    let mut flags = String::new();
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match (arg.as_str(), args.next()) {
            ("--criterion", Some(v)) => criterion = v.into(),
            ("--out", Some(v)) => out = v.into(),
            ("--flags", Some(v)) => flags = format!(" {v}"),
            _ => {
                eprintln!("usage: bench_report [--criterion DIR] [--out FILE] [--flags TEXT]");
                return ExitCode::FAILURE;
            }
        }
    }
    let rows = match collect(&criterion) {
        Ok(rows) if !rows.is_empty() => rows,
        Ok(_) => {
            eprintln!(
                "{}: no criterion results; run `cargo bench` first",
                criterion.display()
            );
            return ExitCode::FAILURE;
        }
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    };
    let files = bench_files(Path::new("benches"));
    let report = render(&rows, &files, &flags);
    if let Err(e) = std::fs::write(&out, report) {
        eprintln!("{}: {e}", out.display());
        return ExitCode::FAILURE;
    }
    println!("{} benchmarks written to {}", rows.len(), out.display());
    ExitCode::SUCCESS
}

/// Every `new/benchmark.json` under `dir`, with its estimates.
fn collect(dir: &Path) -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries = std::fs::read_dir(&d).map_err(|e| format!("{}: {e}", d.display()))?;
        for entry in entries.flatten() {
            let path = entry.path();
            if !path.is_dir() {
                continue;
            }
            if path.file_name().is_some_and(|n| n == "new") {
                if let Some(row) = read_result(&path)? {
                    rows.push(row);
                }
            } else if path
                .file_name()
                .is_none_or(|n| n != "base" && n != "report")
            {
                stack.push(path);
            }
        }
    }
    rows.sort_by(|a, b| (&a.group, &a.name).cmp(&(&b.group, &b.name)));
    Ok(rows)
}

fn read_result(dir: &Path) -> Result<Option<Row>, String> {
    let id_path = dir.join("benchmark.json");
    let est_path = dir.join("estimates.json");
    if !id_path.is_file() || !est_path.is_file() {
        return Ok(None);
    }
    let read = |p: &Path| std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()));
    let id: BenchmarkId = serde_json::from_str(&read(&id_path)?)
        .map_err(|e| format!("{}: {e}", id_path.display()))?;
    let est: Estimates = serde_json::from_str(&read(&est_path)?)
        .map_err(|e| format!("{}: {e}", est_path.display()))?;
    let name = [id.function_id, id.value_str]
        .into_iter()
        .flatten()
        .collect::<Vec<_>>()
        .join("/");
    Ok(Some(Row {
        group: id.group_id,
        name,
        mean_ns: est.mean.point_estimate,
        low_ns: est.mean.confidence_interval.lower_bound,
        high_ns: est.mean.confidence_interval.upper_bound,
        throughput: id.throughput,
    }))
}

/// The benchmark files under `dir`: the first paragraph of each module doc and the group
/// names it passes to `benchmark_group`.
fn bench_files(dir: &Path) -> Vec<BenchFile> {
    let mut files: Vec<BenchFile> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "rs"))
        .filter_map(|e| {
            let src = std::fs::read_to_string(e.path()).ok()?;
            let name = e.path().file_stem()?.to_string_lossy().into_owned();
            let doc = src
                .lines()
                .map_while(|l| l.strip_prefix("//!"))
                .map(str::trim)
                .take_while(|l| !l.is_empty())
                .collect::<Vec<_>>()
                .join(" ");
            let groups = src
                .split("benchmark_group(\"")
                .skip(1)
                .filter_map(|s| s.split('"').next())
                .map(str::to_owned)
                .collect();
            Some(BenchFile { name, doc, groups })
        })
        .collect();
    files.sort_by(|a, b| a.name.cmp(&b.name));
    files
}

/// The report: `flags` (empty, or starting with a space) are the arguments the benches were
/// run with, written into each command.
fn render(rows: &[Row], files: &[BenchFile], flags: &str) -> String {
    let mut md = String::from("# Benchmarks\n\n");
    let _ = writeln!(
        md,
        "Criterion's last run of each benchmark, written by \
         `cargo run --no-default-features --example bench_report` from `target/criterion`. \
         Run a file's benchmarks with the command under its heading \
         (`plugin` needs the default `bevy` feature). Compare figures within one run only: \
         the machine's load moves between runs.\n\nMachine: {}.\n",
        machine()
    );
    let mut by_file: BTreeMap<&str, Vec<&Row>> = BTreeMap::new();
    for row in rows {
        let file = files
            .iter()
            .find(|f| f.groups.contains(&row.group))
            .map_or("other", |f| f.name.as_str());
        by_file.entry(file).or_default().push(row);
    }
    for (file, rows) in by_file {
        let _ = writeln!(md, "## {file}\n");
        if let Some(f) = files.iter().find(|f| f.name == file) {
            let _ = writeln!(
                md,
                "{}\n\n`cargo bench --no-default-features --bench {file}{flags}`\n",
                f.doc
            );
        }
        md.push_str("| benchmark | mean | 95 % interval | throughput |\n|---|---|---|---|\n");
        for r in rows {
            let _ = writeln!(
                md,
                "| {}/{} | {} | {} – {} | {} |",
                r.group,
                r.name,
                duration(r.mean_ns),
                duration(r.low_ns),
                duration(r.high_ns),
                throughput(r.throughput.as_ref(), r.mean_ns)
            );
        }
        md.push('\n');
    }
    md
}

/// The processor's model and the number of logical cores, and the compiler's version.
fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_owned())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_owned());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let rustc = std::process::Command::new("rustc")
        .arg("--version")
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
        .unwrap_or_default();
    format!(
        "{cpu}, {cores} logical cores, {}; {rustc}",
        std::env::consts::OS
    )
}

fn duration(ns: f64) -> String {
    if ns >= 1e9 {
        format!("{:.2} s", ns / 1e9)
    } else if ns >= 1e6 {
        format!("{:.2} ms", ns / 1e6)
    } else if ns >= 1e3 {
        format!("{:.2} µs", ns / 1e3)
    } else {
        format!("{ns:.1} ns")
    }
}

fn throughput(t: Option<&Throughput>, mean_ns: f64) -> String {
    let per_s = 1e9 / mean_ns;
    match t {
        Some(Throughput::Bytes(n) | Throughput::BytesDecimal(n)) => {
            format!("{:.1} MiB/s", *n as f64 * per_s / (1024.0 * 1024.0))
        }
        Some(Throughput::Elements(n)) => format!("{:.3} M/s", *n as f64 * per_s / 1e6),
        _ => String::new(),
    }
}
