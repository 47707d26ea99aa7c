//! Long calls that honour Ctrl-C.
//!
//! Python runs signal handlers only on the main thread and only between bytecodes, so a call
//! that computes for minutes inside Rust ignores SIGINT. [`interruptible`] runs the work on a
//! scoped worker thread while the calling thread, with the GIL released, waits for it and wakes
//! every [`POLL`] to run the pending handlers (`Python::check_signals`). When one raises
//! (KeyboardInterrupt), the worker is told to stop through its `AtomicBool`, which the core's
//! long loops check between chunks of work (a sky-table azimuth, a map node: milliseconds),
//! and the call returns the handler's exception once the worker has let go of its borrows.
//!
//! Why a worker rather than a hook that checks signals from inside the loops: the hook would
//! need the GIL on rayon's threads, and `PyErr_CheckSignals` does nothing off the main thread.
//! The worker costs one thread spawn per call (tens of microseconds).

use crate::errors::{CoreError, SkyfallError};
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::{Mutex, OnceLock};
use std::time::Duration;

/// How often the waiting thread runs Python's signal handlers.
pub const POLL: Duration = Duration::from_millis(50);

/// rayon's global pool, started on the first call that needs it. rayon builds it lazily and
/// panics when it cannot (its threads refused under a memory limit); built here, a failure is a
/// `MemoryError` instead, and stays one: rayon cannot try again in this process.
fn ensure_pool() -> PyResult<()> {
    static FAILED: OnceLock<Option<String>> = OnceLock::new();
    let failed = FAILED.get_or_init(|| match rayon::ThreadPoolBuilder::new().build_global() {
        Ok(()) => None,
        // Built already (by an earlier call, or another library in this process): fine.
        Err(e) if rayon::current_thread_index().is_some() || e.to_string().contains("already") => {
            None
        }
        Err(e) => Some(e.to_string()),
    });
    match failed {
        None => Ok(()),
        Some(msg) => Err(pyo3::exceptions::PyMemoryError::new_err(format!(
            "skyfall could not start its worker threads (out of memory or of threads): {msg}"
        ))),
    }
}

/// Runs `work` with the GIL released, honouring Ctrl-C (see the module docs). `work` gets the
/// flag to pass to the core's cancellable functions; its result comes back as it is, unless
/// a signal handler raised, whose exception is returned instead.
pub fn interruptible<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce(&AtomicBool) -> T + Send,
{
    ensure_pool()?;
    let cancel = AtomicBool::new(false);
    let slot = Mutex::new(Some(work));
    let take = || slot.lock().ok().and_then(|mut w| w.take());
    let (done_tx, done_rx) = mpsc::sync_channel::<()>(1);
    std::thread::scope(|s| {
        let (take, cancel_ref) = (&take, &cancel);
        let spawned = std::thread::Builder::new()
            .name("skyfall-work".into())
            // `move`: the worker owns the sender, so a panic drops it and the wait below sees
            // the channel disconnect (borrowed, it outlived a panicking worker: a hang).
            .spawn_scoped(s, move || {
                let out = take().map(|w| w(cancel_ref));
                // The receiver outlives this thread (it is joined below).
                let _ = done_tx.send(());
                out
            });
        let handle = match spawned {
            Ok(h) => h,
            // No thread to be had (an exhausted machine): the work runs here, uninterruptible.
            Err(_) => {
                return match take() {
                    Some(w) => Ok(py.detach(|| w(&cancel))),
                    None => Err(SkyfallError::new_err("internal: the work was taken twice")),
                };
            }
        };
        let mut raised: Option<PyErr> = None;
        // (A Receiver is not Sync: it travels into each wait and back.)
        let mut rx = done_rx;
        loop {
            let (r, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
            rx = back;
            match r {
                Ok(()) | Err(mpsc::RecvTimeoutError::Disconnected) => break,
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if let Err(e) = py.check_signals() {
                        cancel.store(true, Ordering::Relaxed);
                        raised = Some(e);
                        // The worker stops at its next check; wait for it without the GIL.
                        let _ = py.detach(move || rx.recv());
                        break;
                    }
                }
            }
        }
        let joined = py.detach(|| handle.join());
        match (raised, joined) {
            (Some(e), _) => Err(e),
            (None, Ok(Some(out))) => Ok(out),
            (None, Ok(None)) => Err(SkyfallError::new_err("internal: the work was taken twice")),
            (None, Err(panic)) => {
                let msg = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "a panic".into());
                if msg.contains("ThreadPoolBuildError") {
                    // rayon could not start its threads: the process is out of memory or threads.
                    return Err(pyo3::exceptions::PyMemoryError::new_err(format!(
                        "skyfall could not start its worker threads (out of memory or of threads): {msg}"
                    )));
                }
                Err(SkyfallError::new_err(format!(
                    "internal error in skyfall's core (a bug: please report it): {msg}"
                )))
            }
        }
    })
}

/// Work below this many elementary steps (points × azimuths, for the sky) runs inline with the
/// GIL released: it ends within about 0.1 s anyway, and the worker thread would cost it a
/// measurable share (1000 points at 16 azimuths: 1.6 ms inline, 2.6 ms through the worker).
pub const INLINE_STEPS: u128 = 1 << 20;

/// [`interruptible`] for work that returns a core result; `steps` estimates its size (work
/// under [`INLINE_STEPS`] runs inline, uninterruptible and without the worker's overhead).
pub fn interruptible_core<T, F>(py: Python<'_>, steps: u128, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce(&AtomicBool) -> skyfall_core::Result<T> + Send,
{
    ensure_pool()?;
    if steps < INLINE_STEPS {
        let never = AtomicBool::new(false);
        return Ok(py.detach(|| work(&never)).map_err(CoreError)?);
    }
    Ok(interruptible(py, work)?.map_err(CoreError)?)
}
