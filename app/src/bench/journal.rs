//! What a `clothlab bench` run has measured so far, kept as it goes: `cells.jsonl` in the
//! output folder, one JSON object a line — first the plan, then every finished cell (one
//! round of one job at one size), every cell skipped over the budget and every API's
//! overhead benchmarks — each line flushed and synced when written. A run that is stopped
//! (Ctrl-C, `kill`, a crash) keeps every cell it finished; `bench --resume DIR` reads them
//! back, checks that the plan is the same, and measures only what is missing.

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::{Context, Result, bail};
use clothlab::core::timing::OverheadRow;
use serde::{Deserialize, Serialize};

use super::results::Cell;

/// The journal's file name in the output folder.
pub const FILE: &str = "cells.jsonl";

/// What a run measures and where: a resumed run must have the same, or its cells would
/// not belong in one report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// The command line that made it (not compared: a resumed run's differs by `--resume`).
    pub command: String,
    /// clothlab's version and this binary's size and modification time: another build
    /// may measure something else.
    pub build: String,
    /// The machine's label.
    pub machine: String,
    /// wgpu's adapter, if any.
    pub wgpu_adapter: Option<String>,
    /// The Vulkan device, if any.
    pub vulkan_adapter: Option<String>,
    /// The OpenGL context, if any (absent in journals from before GL).
    #[serde(default)]
    pub gl_adapter: Option<String>,
    /// The jobs of every size (backends, or the ladder's rungs), by their cells' names.
    pub jobs: Vec<String>,
    /// Grid sizes.
    pub sizes: Vec<u32>,
    /// Frames measured per table and cell.
    pub frames: u32,
    /// Rounds of every cell.
    pub repeat: u32,
    /// The offscreen render target.
    pub resolution: (u32, u32),
    /// The cell budget, s.
    pub cell_budget: f64,
    /// Whether the overhead benchmarks run.
    pub overhead: bool,
    /// The simulation parameters and scene, as JSON.
    pub setup: serde_json::Value,
}

impl Plan {
    /// The first field in which `self` (the stored plan) and `now` differ, as
    /// `name: stored … here …`.
    fn difference(&self, now: &Plan) -> Option<String> {
        let (a, b) = (serde_json::to_value(self).ok()?, serde_json::to_value(now).ok()?);
        let (a, b) = (a.as_object()?, b.as_object()?);
        a.iter().filter(|(k, _)| k.as_str() != "command").find(|(k, v)| b.get(*k) != Some(v)).map(|(k, v)| {
            let show = |x: Option<&serde_json::Value>| {
                let s = x.map(|x| x.to_string()).unwrap_or_default();
                if s.chars().count() > 80 { format!("{}…", s.chars().take(80).collect::<String>()) } else { s }
            };
            format!("{k}: {} there, {} here", show(Some(v)), show(b.get(k)))
        })
    }

    /// The build's identity: version, and the binary's size and modification time.
    pub fn build_id() -> String {
        let exe = std::env::current_exe().ok().and_then(|p| std::fs::metadata(p).ok());
        let stamp = exe
            .map(|m| {
                let t = m.modified().ok().and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok());
                format!("{} bytes, modified {}", m.len(), t.map(|d| d.as_secs()).unwrap_or(0))
            })
            .unwrap_or_default();
        format!("{} ({stamp})", env!("CARGO_PKG_VERSION"))
    }
}

/// One line of the journal.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Entry {
    Plan(Plan),
    Cell {
        n: u32,
        job: String,
        round: u32,
        cell: Cell,
    },
    Skipped {
        n: u32,
        job: String,
        line: String,
    },
    Overhead {
        api: String,
        adapter: String,
        rows: Vec<OverheadRow>,
    },
    /// The run ended (completed, or stopped with its report written after the last cell
    /// it could take); a journal without it is a run killed mid-way.
    Done {
        complete: bool,
    },
}

/// What a journal file holds.
#[derive(Default)]
struct Contents {
    plan: Option<Plan>,
    cells: HashMap<(u32, String, u32), Cell>,
    skipped: HashMap<(u32, String), String>,
    overhead: HashMap<String, (String, Vec<OverheadRow>)>,
    /// The last `Done` entry's `complete`, if any.
    done: Option<bool>,
}

/// Reads the journal at `path`. A line cut short by a kill is the last one: it is skipped,
/// and what it held is measured again.
fn read(path: &Path) -> Result<Contents> {
    let file = File::open(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut c = Contents::default();
    for (i, line) in BufReader::new(file).lines().enumerate() {
        let line = line.with_context(|| format!("cannot read {}", path.display()))?;
        if line.trim().is_empty() {
            continue;
        }
        let Ok(entry) = serde_json::from_str::<Entry>(&line) else {
            log::warn!("{}:{}: not a whole entry; measured again", path.display(), i + 1);
            continue;
        };
        match entry {
            Entry::Plan(p) => c.plan = Some(p),
            Entry::Cell { n, job, round, cell } => {
                c.cells.insert((n, job, round), cell);
            }
            Entry::Skipped { n, job, line } => {
                c.skipped.insert((n, job), line);
            }
            Entry::Overhead { api, adapter, rows } => {
                c.overhead.insert(api, (adapter, rows));
            }
            Entry::Done { complete } => c.done = Some(complete),
        }
    }
    Ok(c)
}

/// The journal of a run: what was already there (when resumed) and the open file that
/// every new entry is appended to.
pub struct Journal {
    path: PathBuf,
    file: File,
    cells: HashMap<(u32, String, u32), Cell>,
    skipped: HashMap<(u32, String), String>,
    overhead: HashMap<String, (String, Vec<OverheadRow>)>,
}

impl Journal {
    /// A new journal in `dir` for `plan`. The journal of a finished run there is
    /// replaced; one of a stopped run (its cells not yet in a complete report) is refused
    /// in one line, so that hours of measurement are not lost to a run started without
    /// `--resume`.
    pub fn create(dir: &Path, plan: &Plan) -> Result<Journal> {
        let path = dir.join(FILE);
        if path.is_file() {
            let old = read(&path)?;
            if old.done != Some(true) && !old.cells.is_empty() {
                bail!(
                    "{} holds a stopped run's {} cells: `--resume {}` with its options (`{}`) finishes it; delete {} to start over",
                    dir.display(),
                    old.cells.len(),
                    dir.display(),
                    old.plan.map(|p| p.command).unwrap_or_default(),
                    path.display()
                );
            }
        }
        let file = File::create(&path).with_context(|| format!("cannot write {}", path.display()))?;
        let mut j = Journal { path, file, cells: HashMap::new(), skipped: HashMap::new(), overhead: HashMap::new() };
        j.append(&Entry::Plan(plan.clone()))?;
        Ok(j)
    }

    /// The journal of the stopped run in `dir`, refused in one line when its plan is not
    /// `plan`; new entries go on at its end.
    pub fn resume(dir: &Path, plan: &Plan) -> Result<Journal> {
        let path = dir.join(FILE);
        let old = read(&path)?;
        let Some(stored) = old.plan else { bail!("--resume {}: {FILE} has no plan", dir.display()) };
        if let Some(d) = stored.difference(plan) {
            bail!(
                "--resume {}: this run's plan differs from the stopped one's ({d}); resume with the stopped run's options (`{}`) on the same machine and build",
                dir.display(),
                stored.command
            );
        }
        let file =
            File::options().append(true).open(&path).with_context(|| format!("cannot write {}", path.display()))?;
        Ok(Journal { path, file, cells: old.cells, skipped: old.skipped, overhead: old.overhead })
    }

    fn append(&mut self, e: &Entry) -> Result<()> {
        let mut line = serde_json::to_string(e)?;
        line.push('\n');
        self.file
            .write_all(line.as_bytes())
            .and_then(|_| self.file.sync_data())
            .with_context(|| format!("cannot write {}", self.path.display()))
    }

    /// The cell of `job` at size `n` in `round`, if the stopped run measured it.
    pub fn cell(&self, n: u32, job: &str, round: u32) -> Option<Cell> {
        self.cells.get(&(n, job.to_owned(), round)).cloned()
    }

    /// Why `job` at size `n` was skipped, if the stopped run skipped it.
    pub fn skipped(&self, n: u32, job: &str) -> Option<String> {
        self.skipped.get(&(n, job.to_owned())).cloned()
    }

    /// The overhead benchmarks of `api`, if the stopped run finished them.
    pub fn overhead(&self, api: &str) -> Option<(String, Vec<OverheadRow>)> {
        self.overhead.get(api).cloned()
    }

    /// Cells read back from a stopped run.
    pub fn resumed_cells(&self) -> usize {
        self.cells.len()
    }

    /// Records a finished cell.
    pub fn add_cell(&mut self, n: u32, job: &str, round: u32, cell: &Cell) -> Result<()> {
        self.append(&Entry::Cell { n, job: job.to_owned(), round, cell: cell.clone() })
    }

    /// Records a cell skipped over the budget.
    pub fn add_skipped(&mut self, n: u32, job: &str, line: &str) -> Result<()> {
        self.append(&Entry::Skipped { n, job: job.to_owned(), line: line.to_owned() })
    }

    /// Records the end of the run: `complete` when every cell and overhead benchmark is
    /// in its report.
    pub fn finish(&mut self, complete: bool) -> Result<()> {
        self.append(&Entry::Done { complete })
    }

    /// Records an API's overhead benchmarks.
    pub fn add_overhead(&mut self, api: &str, adapter: &str, rows: &[OverheadRow]) -> Result<()> {
        self.append(&Entry::Overhead { api: api.to_owned(), adapter: adapter.to_owned(), rows: rows.to_vec() })
    }
}

/// Set by SIGINT or SIGTERM: the run stops after the cell in progress.
static STOP: AtomicBool = AtomicBool::new(false);

/// Installs the handler: the first SIGINT/SIGTERM asks the run to stop after its cell, a
/// second one ends the process at once (exit 130).
pub fn catch_signals() {
    let installed = ctrlc::set_handler(|| {
        if STOP.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!("\nstopping after the cell in progress (again to stop at once)");
    });
    if let Err(e) = installed {
        log::warn!("Ctrl-C will stop the bench at once, without its report: {e}");
    }
}

/// Whether a stop was asked for.
pub fn stopping() -> bool {
    STOP.load(Ordering::SeqCst)
}
