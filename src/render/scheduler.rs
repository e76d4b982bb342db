//! The pass scheduler every render goes through: a worker pool, passes of samples per pixel sized
//! to the sample target or the time budget, a progress bar, and cancellation (Ctrl-C) between
//! work items. Camera-ray integrators render passes of tiles, the light tracer passes of light
//! path chunks; both hand the scheduler a function that renders one work item of a pass and a
//! function that merges a pass's results, in item order, into the film.
//!
//! Pass sizes: without a time budget, passes end at fixed sample counts whatever the target:
//! 1, 2, 4, … up to `max_pass`, then every multiple of it (the last pass stops at the target); with one, one sample first, then as many whole samples as fit in
//! the remaining time at the rate measured so far (at most `max_pass`), stopping when not even
//! one fits. Determinism does not depend on the thread count: results are merged in item order.

use super::{RenderError, RenderSettings};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// What a run of passes did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Passes {
    /// Samples per pixel of the passes that completed.
    pub done: u32,
    /// Whether cancellation stopped a pass before it completed.
    pub interrupted: bool,
    /// Wall-clock time of all passes.
    pub elapsed: Duration,
}

/// A render's schedule: its settings, the cancellation flag, the worker pool and progress bar.
pub struct Scheduler<'a> {
    settings: &'a RenderSettings,
    cancel: &'a AtomicBool,
    pool: rayon::ThreadPool,
    unit: &'static str,
    /// Work units (samples, light paths) per sample per pixel, for the progress bar and the
    /// rate it shows.
    work_per_spp: u64,
}

impl<'a> Scheduler<'a> {
    /// A schedule for `settings` whose passes do `work_per_spp` units of `unit` per sample per
    /// pixel. Fails if the worker threads cannot start.
    pub fn new(
        settings: &'a RenderSettings,
        cancel: &'a AtomicBool,
        work_per_spp: u64,
        unit: &'static str,
    ) -> Result<Scheduler<'a>, RenderError> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(settings.threads)
            .build()
            .map_err(|e| RenderError::Threads { threads: settings.threads, message: e.to_string() })?;
        Ok(Scheduler { settings, cancel, pool, unit, work_per_spp })
    }

    /// Runs passes until `spp` samples per pixel are done, the time budget is used or the render
    /// is cancelled. Each pass calls `item(k, first, count)` for every work item `k < items` in
    /// parallel (samples `first .. first + count` of each pixel; it returns its result and the
    /// work units it did), then `merge(results, count)` in item order, where a `None` result is
    /// an item that cancellation skipped. Passes hold at most `max_pass` samples per pixel.
    pub fn run<W: Send>(
        &self,
        spp: u32,
        max_pass: u32,
        items: usize,
        item: impl Fn(usize, u32, u32) -> (W, u64) + Sync,
        merge: impl FnMut(Vec<Option<W>>, u32) -> ControlFlow<()>,
    ) -> Passes {
        self.run_from(0, spp, max_pass, items, item, merge)
    }

    /// [`Scheduler::run`] continuing a render that has `start` samples per pixel already (a
    /// resumed checkpoint): passes take samples `start ..`. `merge` returning
    /// `ControlFlow::Break` ends the run after that pass (adaptive sampling: every pixel done).
    pub fn run_from<W: Send>(
        &self,
        start: u32,
        spp: u32,
        max_pass: u32,
        items: usize,
        item: impl Fn(usize, u32, u32) -> (W, u64) + Sync,
        mut merge: impl FnMut(Vec<Option<W>>, u32) -> ControlFlow<()>,
    ) -> Passes {
        let spp = spp.max(1);
        let (bar, bar_len) = self.progress_bar(spp.saturating_sub(start));
        let started = Instant::now();
        let work_done = AtomicU64::new(0);
        let mut done = start;
        let mut interrupted = false;
        while done < spp {
            let Some(pass) = self.pass_size(spp, done, start, max_pass, started.elapsed()) else { break };
            let results: Vec<Option<W>> = self.pool.install(|| {
                (0..items)
                    .into_par_iter()
                    .map(|k| {
                        if self.cancel.load(Ordering::Relaxed) {
                            return None;
                        }
                        let (w, n) = item(k, done, pass);
                        let total = work_done.fetch_add(n, Ordering::Relaxed) + n;
                        match self.settings.time_budget {
                            Some(_) => bar.set_position((started.elapsed().as_millis() as u64).min(bar_len)),
                            None => bar.inc(n),
                        }
                        if self.settings.progress {
                            let secs = started.elapsed().as_secs_f64().max(1e-9);
                            bar.set_message(format!("{:.2} M {}/s", total as f64 / secs / 1e6, self.unit));
                        }
                        Some(w)
                    })
                    .collect()
            });
            let complete = results.iter().all(Option::is_some);
            let flow = merge(results, pass);
            if !complete {
                interrupted = true;
                break;
            }
            done += pass;
            if flow.is_break() {
                break;
            }
        }
        bar.finish_and_clear();
        Passes { done, interrupted, elapsed: started.elapsed() }
    }

    /// Samples per pixel of the next pass, or `None` when the time budget has no room for one.
    fn pass_size(&self, spp: u32, done: u32, start: u32, max_pass: u32, elapsed: Duration) -> Option<u32> {
        let remaining_spp = spp - done;
        match self.settings.time_budget {
            // Progressive, at boundaries that do not depend on the target: 1, 2, 4, … up to
            // `max_pass`, then multiples of it. An early interruption still has the whole
            // frame, and a render resumed from a boundary continues exactly as one that never
            // stopped.
            None => Some((next_boundary(done, max_pass) - done).min(remaining_spp)),
            Some(budget) => {
                if elapsed >= budget {
                    return None;
                }
                let run = done - start;
                if run == 0 {
                    return Some(1);
                }
                // Whole samples that fit in the remaining time, at the rate measured in this run.
                let per_spp = elapsed.as_secs_f64() / run as f64;
                let fit = ((budget - elapsed).as_secs_f64() / per_spp.max(1e-9)).floor() as u32;
                (fit > 0).then(|| fit.min(max_pass).min(remaining_spp))
            }
        }
    }

    /// The progress bar (hidden unless `settings.progress`) and its length: with a time budget it
    /// measures milliseconds of the budget, else the work of `spp` samples per pixel.
    fn progress_bar(&self, spp: u32) -> (ProgressBar, u64) {
        let len = match self.settings.time_budget {
            Some(b) => b.as_millis().max(1) as u64,
            None => self.work_per_spp * spp as u64,
        };
        if !self.settings.progress {
            return (ProgressBar::hidden(), len);
        }
        let bar = ProgressBar::new(len);
        bar.set_draw_target(ProgressDrawTarget::stderr_with_hz(4));
        let template = if self.settings.time_budget.is_some() {
            "{spinner} [{elapsed_precise}] {wide_bar} time budget {percent}% {msg}".to_string()
        } else {
            format!("{{spinner}} [{{elapsed_precise}}] {{wide_bar}} {{pos}}/{{len}} {}, ETA {{eta}} {{msg}}", self.unit)
        };
        bar.set_style(ProgressStyle::with_template(&template).expect("valid template"));
        (bar, len)
    }
}

/// The first pass boundary after `done` samples per pixel: 1, 2, 4, … up to `max_pass`, then
/// the multiples of `max_pass`.
fn next_boundary(done: u32, max_pass: u32) -> u32 {
    let max_pass = max_pass.max(1);
    if done < max_pass {
        let mut b = 1u32;
        while b <= done {
            b *= 2;
        }
        b.min(max_pass)
    } else {
        (done / max_pass + 1).saturating_mul(max_pass)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pass sizes follow the sample target (an eighth of it, 1 to `max_pass`, the last pass the
    /// rest); items are merged in order; cancellation stops the run and reports it.
    #[test]
    fn passes_cover_the_target_in_order() {
        let settings = RenderSettings { threads: 2, ..Default::default() };
        let never = AtomicBool::new(false);
        let s = Scheduler::new(&settings, &never, 10, "things").unwrap();
        let mut passes = Vec::new();
        let out = s.run(
            100,
            16,
            7,
            |k, first, count| ((k, first, count), 1),
            |results, count| {
                let got: Vec<usize> = results.iter().map(|r| r.unwrap().0).collect();
                assert_eq!(got, (0..7).collect::<Vec<_>>(), "merged in item order");
                passes.push(count);
                ControlFlow::Continue(())
            },
        );
        assert_eq!(out.done, 100);
        assert!(!out.interrupted);
        // Boundaries at 1, 2, 4, 8, 16, then every 16, whatever the target; the last pass stops
        // at the target; a continued run keeps the same boundaries.
        assert_eq!(passes, [1, 1, 2, 4, 8, 16, 16, 16, 16, 16, 4]);
        let mut continued = Vec::new();
        let out = s.run_from(20, 50, 16, 2, |_, _, _| ((), 1), |_, count| {
            continued.push(count);
            ControlFlow::Continue(())
        });
        assert_eq!((out.done, continued), (50, vec![12, 16, 2]));
        let light = s.run(5, 1, 3, |_, _, _| ((), 1), |_, count| {
            assert_eq!(count, 1);
            ControlFlow::Continue(())
        });
        assert_eq!(light.done, 5);
        // A merge that says stop ends the run after its pass, not as an interruption.
        let stopped = s.run(100, 16, 2, |_, _, _| ((), 1), |_, _| ControlFlow::Break(()));
        assert_eq!((stopped.done, stopped.interrupted), (1, false));
        let cancelled = AtomicBool::new(true);
        let s = Scheduler::new(&settings, &cancelled, 10, "things").unwrap();
        let out = s.run(100, 16, 4, |_, _, _| ((), 1), |results, _| {
            assert!(results.iter().all(Option::is_none));
            ControlFlow::Continue(())
        });
        assert!(out.interrupted && out.done == 0);
    }

    #[test]
    fn time_budget_sizes_passes_by_the_measured_rate() {
        let settings = RenderSettings { time_budget: Some(Duration::from_millis(100)), ..Default::default() };
        let never = AtomicBool::new(false);
        let s = Scheduler::new(&settings, &never, 1, "things").unwrap();
        assert_eq!(s.pass_size(1000, 0, 0, 16, Duration::ZERO), Some(1));
        // 10 ms per sample so far, 60 ms left: 6 fit.
        assert_eq!(s.pass_size(1000, 4, 0, 16, Duration::from_millis(40)), Some(6));
        assert_eq!(s.pass_size(1000, 4, 0, 2, Duration::from_millis(40)), Some(2));
        assert_eq!(s.pass_size(1000, 9, 0, 16, Duration::from_millis(95)), None, "not one more fits");
        assert_eq!(s.pass_size(1000, 9, 0, 16, Duration::from_millis(120)), None);
    }
}
