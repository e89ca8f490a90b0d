//! The `--json`, `--trace`, `--vcd` and `--plot` files of one run, opened,
//! fed and closed in one place so a front end (`cargo xtask sim`) is a
//! few lines: load the machine, read the job, call [`simulate`], print
//! [`crate::report::print_summary`].

use std::fs::File;
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};

use burin::AXES;

use crate::config::MachineConfig;
use crate::plot::SvgPlot;
use crate::record::{PathKind, PinEvent, Recorder, RunInfo, Summary, Tee};
use crate::report::JsonReport;
use crate::trace::TraceCsv;
use crate::vcd::Vcd;

/// Which files to write; `None` skips that writer entirely.
#[derive(Clone, Debug, Default)]
pub struct Outputs {
    pub json: Option<PathBuf>,
    pub trace: Option<PathBuf>,
    pub vcd: Option<PathBuf>,
    pub plot: Option<PathBuf>,
}

fn create(path: &Path) -> io::Result<BufWriter<File>> {
    File::create(path)
        .map(|f| BufWriter::with_capacity(1 << 20, f))
        .map_err(|e| io::Error::new(e.kind(), format!("{}: {e}", path.display())))
}

/// Forwards to a writer and keeps the first error of its `finish`, which
/// the engine has nowhere to report.
struct Named<'a> {
    path: &'a Path,
    rec: &'a mut dyn Recorder,
    error: Option<io::Error>,
}

impl Recorder for Named<'_> {
    fn start(&mut self, info: &RunInfo) {
        self.rec.start(info);
    }
    fn step_event(&mut self, ev: &PinEvent) {
        self.rec.step_event(ev);
    }
    fn step_fall(&mut self, tick: u64, mask: u8) {
        self.rec.step_fall(tick, mask);
    }
    fn commanded(&mut self, line: u32, kind: PathKind, to_mm: [f32; AXES]) {
        self.rec.commanded(line, kind, to_mm);
    }
    fn velocity(&mut self, tick: u64, mm_per_min: f32) {
        self.rec.velocity(tick, mm_per_min);
    }
    fn finish(&mut self, summary: &Summary) -> io::Result<()> {
        if let Err(e) = self.rec.finish(summary) {
            let e = io::Error::new(e.kind(), format!("{}: {e}", self.path.display()));
            self.error.get_or_insert(e);
        }
        Ok(())
    }
}

/// Runs `source` on the machine `cfg` (streamed through the virtual
/// board, see [`crate::offline`]), writing the requested files.
/// Every file is created before the run starts, so a bad path fails fast;
/// a write error comes back naming its file.
pub fn simulate(
    cfg: &MachineConfig,
    source: &str,
    job_name: &str,
    out: &Outputs,
) -> io::Result<Summary> {
    let mut json = out
        .json
        .as_deref()
        .map(create)
        .transpose()?
        .map(JsonReport::new);
    let mut trace = out
        .trace
        .as_deref()
        .map(create)
        .transpose()?
        .map(TraceCsv::new);
    let mut vcd = out.vcd.as_deref().map(create).transpose()?.map(Vcd::new);
    let mut plot = match out.plot.as_deref() {
        Some(p) => Some(SvgPlot::new(create(p)?, job_name)),
        None => None,
    };
    let mut named: Vec<Named> = Vec::new();
    let slots: [(Option<&Path>, Option<&mut dyn Recorder>); 4] = [
        (
            out.json.as_deref(),
            json.as_mut().map(|r| r as &mut dyn Recorder),
        ),
        (
            out.trace.as_deref(),
            trace.as_mut().map(|r| r as &mut dyn Recorder),
        ),
        (
            out.vcd.as_deref(),
            vcd.as_mut().map(|r| r as &mut dyn Recorder),
        ),
        (
            out.plot.as_deref(),
            plot.as_mut().map(|r| r as &mut dyn Recorder),
        ),
    ];
    for (path, rec) in slots {
        if let (Some(path), Some(rec)) = (path, rec) {
            named.push(Named {
                path,
                rec,
                error: None,
            });
        }
    }
    let summary = {
        let mut tee = Tee(named.iter_mut().map(|n| n as &mut dyn Recorder).collect());
        crate::offline::run_file(cfg, source, &mut tee)
    };
    match named.into_iter().find_map(|n| n.error) {
        Some(e) => Err(e),
        None => Ok(summary),
    }
}
