//! Stopping a long kernel early: the user asked to (Python's Ctrl-C, which the extension sees
//! while it waits for a kernel). The caller raises a flag with [`request`]; the long kernels —
//! exact geodesics, the isometric match, grinding paths and their simulated pass — look at it
//! between units of their work ([`check`]) and give up with `Error::Interrupted`. What a kernel
//! computes never depends on the flag: it either finishes as it would have or returns the error.
//!
//! The flag is process-wide (a Ctrl-C stops every long call under way) and lowered when the last
//! call that could see it ends ([`Watch`]), so it never reaches a later call.
use crate::error::{Error, Result};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);
static WATCHING: AtomicUsize = AtomicUsize::new(0);

/// Asks the long kernels under way to stop.
pub fn request() {
    REQUESTED.store(true, Ordering::Relaxed);
}

/// Whether a stop was asked for.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::Relaxed)
}

/// `Err(Error::Interrupted)` once a stop was asked for.
pub fn check() -> Result<()> {
    if requested() {
        Err(Error::Interrupted)
    } else {
        Ok(())
    }
}

/// A call during which a stop may be asked for: the flag is lowered when the last such call
/// ends.
pub struct Watch(());

impl Watch {
    #[allow(clippy::new_without_default)]
    pub fn new() -> Self {
        WATCHING.fetch_add(1, Ordering::AcqRel);
        Watch(())
    }
}

impl Drop for Watch {
    fn drop(&mut self) {
        if WATCHING.fetch_sub(1, Ordering::AcqRel) == 1 {
            REQUESTED.store(false, Ordering::Relaxed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_request_stops_checks_until_the_last_watch_ends() {
        let outer = Watch::new();
        assert!(check().is_ok());
        let inner = Watch::new();
        request();
        assert_eq!(check(), Err(Error::Interrupted));
        drop(inner);
        assert!(requested(), "a call still under way keeps the request");
        drop(outer);
        assert!(check().is_ok(), "the next call starts clear");
    }
}
