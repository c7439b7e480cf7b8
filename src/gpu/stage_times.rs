//! With the `stage-times` feature: where a bidirectional pass's time goes on a given GPU. After
//! each stage of an iteration (light subpaths, the grid's steps, camera subpaths, resolve, and
//! the pass's readback) the host waits for the GPU and adds the wall time since the last mark
//! to that stage, so the stages no longer overlap with the host's next submissions; the sum is
//! the pass's time with that overlap removed. A renderer that marked anything prints the table
//! when it is dropped (a bench row's includes its warm-up pass; `grid_check`'s grid marks count
//! from the last pass). Off in every normal build: the waits cost throughput.

use std::cell::RefCell;
use std::time::Instant;

#[derive(Default)]
pub struct StageTimes {
    last: RefCell<Option<Instant>>,
    seconds: RefCell<Vec<(&'static str, f64, u64)>>,
}

impl StageTimes {
    /// Starts timing from now (the next mark counts from here).
    pub fn start(&self) {
        *self.last.borrow_mut() = Some(Instant::now());
    }

    /// Waits for the GPU's queued work and adds the time since the last mark to `stage`.
    pub fn mark(&self, device: &wgpu::Device, stage: &'static str) {
        let _ = device.poll(wgpu::PollType::wait_indefinitely());
        let now = Instant::now();
        let Some(last) = self.last.borrow_mut().replace(now) else {
            return;
        };
        let dt = (now - last).as_secs_f64();
        let mut s = self.seconds.borrow_mut();
        match s.iter_mut().find(|(n, _, _)| *n == stage) {
            Some(e) => {
                e.1 += dt;
                e.2 += 1;
            }
            None => s.push((stage, dt, 1)),
        }
    }

    /// Whether any stage was timed.
    pub fn is_empty(&self) -> bool {
        self.seconds.borrow().is_empty()
    }

    /// The table: each stage's seconds, share and count of marks.
    pub fn report(&self) -> String {
        let s = self.seconds.borrow();
        let total: f64 = s.iter().map(|e| e.1).sum();
        let mut out = format!("stage times, {total:.4} s in all:\n");
        for (name, secs, n) in s.iter() {
            out += &format!(
                "  {name:<16} {secs:>9.4} s {:>6.1} %  {n:>6} marks, {:>9.1} us each\n",
                100.0 * secs / total.max(1e-12),
                1e6 * secs / *n as f64
            );
        }
        out
    }
}
