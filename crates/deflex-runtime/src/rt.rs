//! Real-time scheduling for the loop threads: SCHED_FIFO for the calling thread and locked
//! memory (mlockall), both best-effort. Without the privilege (EPERM, e.g. no CAP_SYS_NICE or
//! rtprio limit) the caller gets a warning string and the loop continues with normal scheduling.

/// Why a real-time request was not granted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RtUnavailable {
    /// The OS has no such call (not Linux).
    NotSupported,
    /// The call failed with this OS error number (EPERM: no CAP_SYS_NICE, rtprio limit, …).
    Os(i32),
}

impl std::fmt::Display for RtUnavailable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RtUnavailable::NotSupported => f.write_str("not supported on this OS"),
            RtUnavailable::Os(code) => {
                write!(f, "{}", std::io::Error::from_raw_os_error(*code))
            }
        }
    }
}

impl std::error::Error for RtUnavailable {}

/// Outcome of [`try_realtime`]: `Ok` or the reason it was not possible.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RtReport {
    /// SCHED_FIFO for the current thread.
    pub fifo: Result<(), RtUnavailable>,
    /// mlockall(MCL_CURRENT | MCL_FUTURE) (process-wide; only tried when asked).
    pub mlock: Option<Result<(), RtUnavailable>>,
}

impl RtReport {
    /// Human-readable warnings (empty when everything succeeded).
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if let Err(e) = &self.fifo {
            w.push(format!(
                "real-time scheduling unavailable ({e}); continuing with normal scheduling"
            ));
        }
        if let Some(Err(e)) = &self.mlock {
            w.push(format!(
                "memory locking unavailable ({e}); continuing without"
            ));
        }
        w
    }
}

fn last_os_error() -> RtUnavailable {
    RtUnavailable::Os(std::io::Error::last_os_error().raw_os_error().unwrap_or(0))
}

/// Puts the calling thread under SCHED_FIFO at `priority` (1..=99) and, if `lock_memory`, locks
/// the process memory. Never fails hard.
pub fn try_realtime(priority: i32, lock_memory: bool) -> RtReport {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: plain libc calls on the current thread with a valid, initialised parameter.
        let fifo = unsafe {
            let param = libc::sched_param {
                sched_priority: priority.clamp(1, 99),
            };
            let rc = libc::pthread_setschedparam(libc::pthread_self(), libc::SCHED_FIFO, &param);
            if rc == 0 {
                Ok(())
            } else {
                Err(RtUnavailable::Os(rc))
            }
        };
        let mlock = lock_memory.then(|| {
            // SAFETY: mlockall has no memory-safety preconditions.
            let rc = unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) };
            if rc == 0 {
                Ok(())
            } else {
                Err(last_os_error())
            }
        });
        RtReport { fifo, mlock }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (priority, last_os_error);
        RtReport {
            fifo: Err(RtUnavailable::NotSupported),
            mlock: lock_memory.then_some(Err(RtUnavailable::NotSupported)),
        }
    }
}

static INTERRUPTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

extern "C" fn on_interrupt(_signal: libc::c_int) {
    INTERRUPTED.store(true, std::sync::atomic::Ordering::SeqCst);
}

/// Installs a SIGINT/SIGTERM handler that only sets a flag (async-signal-safe) and returns the
/// flag, so `deflex run` can ramp the correction out cleanly on Ctrl-C.
pub fn interrupt_flag() -> &'static std::sync::atomic::AtomicBool {
    #[cfg(unix)]
    {
        let handler = on_interrupt as extern "C" fn(libc::c_int) as libc::sighandler_t;
        // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
        unsafe {
            libc::signal(libc::SIGINT, handler);
            libc::signal(libc::SIGTERM, handler);
        }
    }
    &INTERRUPTED
}
