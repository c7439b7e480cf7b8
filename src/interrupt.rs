//! Stopping a render from outside. Ctrl-C (SIGINT), SIGTERM (what Slurm's `scancel`, its time
//! limits and preemption, and Kubernetes send) and SIGHUP (a closed terminal) all end the
//! render within about a second: the backends look at the flag between tiles, chunks and GPU
//! dispatches and drop the sample or iteration under way whole (`Backend::pass_until`); the
//! samples finished so far are written and the process exits with the conventional status
//! 128 + the signal's number (130, 143, 129). A second signal exits at
//! once with that status: files already written stay whole, since every output is renamed into
//! place.

use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::sync::Arc;

/// Set when a stop was asked for, and by which signal.
#[derive(Clone, Default)]
pub struct StopRequest {
    flag: Arc<AtomicBool>,
    signal: Arc<AtomicI32>,
}

/// SIGINT's number, the status base for a stop whose signal is unknown.
const SIGINT: i32 = 2;

impl StopRequest {
    /// Installs the handlers for SIGINT, SIGTERM and SIGHUP (Ctrl-C only where there are no
    /// Unix signals). Call once per process.
    pub fn install() -> anyhow::Result<StopRequest> {
        let stop = StopRequest::default();
        stop.listen()?;
        Ok(stop)
    }

    #[cfg(unix)]
    fn listen(&self) -> anyhow::Result<()> {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])?;
        let (flag, signal) = (self.flag.clone(), self.signal.clone());
        // The handler only records the signal; this thread acts on it outside signal context.
        std::thread::Builder::new()
            .name("hexray-signals".into())
            .spawn(move || {
                for s in signals.forever() {
                    if flag.load(Ordering::SeqCst) {
                        std::process::exit(128 + s);
                    }
                    // The signal before the flag: the render loop reads it once it sees the flag.
                    signal.store(s, Ordering::SeqCst);
                    flag.store(true, Ordering::SeqCst);
                }
            })?;
        Ok(())
    }

    #[cfg(not(unix))]
    fn listen(&self) -> anyhow::Result<()> {
        let (flag, signal) = (self.flag.clone(), self.signal.clone());
        ctrlc::set_handler(move || {
            if flag.load(Ordering::SeqCst) {
                std::process::exit(128 + SIGINT);
            }
            signal.store(SIGINT, Ordering::SeqCst);
            flag.store(true, Ordering::SeqCst);
        })?;
        Ok(())
    }

    /// The flag the render loop polls between passes, and the backends within them.
    pub fn flag(&self) -> &AtomicBool {
        &self.flag
    }

    /// The exit status for a render stopped by this request: 128 + the signal's number.
    pub fn exit_status(&self) -> u8 {
        let s = self.signal.load(Ordering::SeqCst);
        (128 + if s > 0 && s < 128 { s } else { SIGINT }) as u8
    }
}
