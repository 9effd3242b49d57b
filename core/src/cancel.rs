//! Cancellation: a request to stop, raised from outside a long computation (a signal
//! handler, another thread, an interpreter's signal check) and polled by the loops that
//! may run long — Newton iterations, sub-steps, the static solver's continuation stages,
//! a scene's setup.
//!
//! A [`Cancel`] is a handle on one shared request: clones see the same request, and the
//! default handle ([`Cancel::none`]) never asks to stop. There are two polls:
//!
//! * [`Cancel::requested`]: whether a stop has been asked. Run loops check it between
//!   steps and stop there, losing nothing.
//! * [`Cancel::abandon`]: whether the work under way must be given up — true once a stop
//!   has been asked and the handle's *grace* has passed since a poll first saw the
//!   request. A loop that sees it returns its `Interrupted` error and its caller rolls
//!   back to the last completed step. The grace lets a short step finish, so that a run
//!   usually still stops exactly at a step boundary, while a long one (a Newton solve
//!   that will not converge, a static solve, a knot fit) stops within the grace plus one
//!   iteration of its loop.
//!
//! Both polls are one relaxed atomic load while no stop is asked (plus a countdown with
//! a hook); only after a request does [`Cancel::abandon`] read the clock.
//!
//! A hook ([`Cancel::with_hook`]) lets a thread raise the request itself — an
//! interpreter that learns of signals only when asked (Python's `PyErr_CheckSignals`,
//! which only its main thread may call). It runs only on the thread that attached it,
//! from inside [`Cancel::requested`] on every [`HOOK_POLLS`]-th poll there, or from
//! [`Cancel::check`] on every call, at most once per [`HOOK_INTERVAL`] of the polling
//! thread's own work (the interval runs from the hook's return, so a hook that has to
//! wait does not make every poll wait). (Polls on other
//! threads — an ensemble's workers — see the request once the hook has raised it.)
//!
//! ```
//! use splinerod_core::Cancel;
//! use std::time::Duration;
//! let cancel = Cancel::new().with_grace(Duration::ZERO);
//! let worker = cancel.clone();
//! assert!(!worker.requested() && !worker.abandon());
//! cancel.cancel();
//! assert!(worker.requested() && worker.abandon());
//! assert!(!Cancel::none().abandon());
//! ```

use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering::Relaxed};
use std::sync::Arc;
use std::thread::ThreadId;
use std::time::{Duration, Instant};

thread_local! {
    /// The polling thread (read without touching its `Thread` handle).
    static THREAD: ThreadId = std::thread::current().id();
}

/// A hook is considered on every this many polls of [`Cancel::requested`].
pub const HOOK_POLLS: u32 = 8;

/// Shortest time between the return of a hook and its next call.
pub const HOOK_INTERVAL: Duration = Duration::from_millis(20);

/// A shared request to stop (module docs). Cheap to clone and to poll.
#[derive(Clone, Default)]
pub struct Cancel {
    shared: Option<Arc<Shared>>,
}

/// What the handles of one request share.
struct Shared {
    /// The request (a signal handler may raise it directly).
    flag: Arc<AtomicBool>,
    /// Time the work under way may go on after a poll first saw the request, ns.
    grace: u64,
    /// The clock's origin.
    origin: Instant,
    /// 1 + ns since `origin` when [`Cancel::abandon`] first saw the request; 0: not yet.
    seen: AtomicU64,
    hook: Option<Hook>,
}

/// A check that may raise the request from the thread that attached it.
struct Hook {
    check: Box<dyn Fn() -> bool + Send + Sync>,
    /// The thread it runs on.
    thread: ThreadId,
    /// Polls left before the hook is considered again.
    countdown: AtomicU32,
    /// ns since `origin` of the last call.
    last: AtomicU64,
}

impl std::fmt::Debug for Cancel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut d = f.debug_struct("Cancel");
        if let Some(s) = &self.shared {
            d.field("requested", &s.flag.load(Relaxed))
                .field("grace", &Duration::from_nanos(s.grace))
                .field("hook", &s.hook.is_some());
        }
        d.finish()
    }
}

impl Cancel {
    /// A handle that never asks to stop (the default).
    pub fn none() -> Self {
        Self::default()
    }

    /// A new request, not raised, without grace: [`Cancel::cancel`] raises it.
    pub fn new() -> Self {
        Self::from_flag(Arc::new(AtomicBool::new(false)))
    }

    /// A request raised when `flag` becomes true (as a signal handler may set it, e.g.
    /// `signal_hook::flag::register`), without grace.
    pub fn from_flag(flag: Arc<AtomicBool>) -> Self {
        Self {
            shared: Some(Arc::new(Shared {
                flag,
                grace: 0,
                origin: Instant::now(),
                seen: AtomicU64::new(0),
                hook: None,
            })),
        }
    }

    /// This request with `grace` between a stop being seen and [`Cancel::abandon`]
    /// saying so (builder style, on a handle not yet shared; a clone keeps the old one).
    pub fn with_grace(self, grace: Duration) -> Self {
        let grace = u64::try_from(grace.as_nanos()).unwrap_or(u64::MAX);
        self.rebuilt(|s| Shared { grace, ..s })
    }

    /// This request, raised also when `check` returns true (module docs); `check` runs
    /// only on the calling thread, when that thread polls.
    pub fn with_hook(self, check: impl Fn() -> bool + Send + Sync + 'static) -> Self {
        let hook = Hook {
            check: Box::new(check),
            thread: THREAD.with(|t| *t),
            countdown: AtomicU32::new(1),
            last: AtomicU64::new(0),
        };
        self.rebuilt(|s| Shared {
            hook: Some(hook),
            ..s
        })
    }

    /// The handle with its shared part replaced by `f` of it (a handle without a
    /// request gets a fresh one first; a shared one is copied without its hook).
    fn rebuilt(self, f: impl FnOnce(Shared) -> Shared) -> Self {
        let Some(shared) = self.shared else {
            return Self::new().rebuilt(f);
        };
        let base = Arc::try_unwrap(shared).unwrap_or_else(|s| Shared {
            flag: s.flag.clone(),
            grace: s.grace,
            origin: s.origin,
            seen: AtomicU64::new(s.seen.load(Relaxed)),
            hook: None,
        });
        Self {
            shared: Some(Arc::new(f(base))),
        }
    }

    /// Whether this handle can ever ask to stop (it is not [`Cancel::none`]).
    pub fn is_active(&self) -> bool {
        self.shared.is_some()
    }

    /// Raises the request (every clone sees it).
    pub fn cancel(&self) {
        if let Some(s) = &self.shared {
            s.flag.store(true, Relaxed);
        }
    }

    /// Whether a stop has been asked (module docs); may call the hook.
    #[inline]
    pub fn requested(&self) -> bool {
        match &self.shared {
            None => false,
            Some(s) => s.flag.load(Relaxed) || s.hook.as_ref().is_some_and(|h| s.call(h, false)),
        }
    }

    /// [`Cancel::requested`], considering the hook on every call (not every
    /// [`HOOK_POLLS`]-th): for the polls between steps, which may be few.
    pub fn check(&self) -> bool {
        match &self.shared {
            None => false,
            Some(s) => s.flag.load(Relaxed) || s.hook.as_ref().is_some_and(|h| s.call(h, true)),
        }
    }

    /// Whether the work under way must be abandoned: a stop has been asked and the
    /// grace has passed since a poll first saw it (module docs).
    #[inline]
    pub fn abandon(&self) -> bool {
        match &self.shared {
            Some(s) if self.requested() => s.grace_passed(),
            _ => false,
        }
    }
}

impl Shared {
    /// ns since the origin, plus 1 (so that 0 means "never").
    fn now(&self) -> u64 {
        u64::try_from(self.origin.elapsed().as_nanos()).unwrap_or(u64::MAX - 1) + 1
    }

    /// Whether the grace has passed since the request was first seen here.
    #[cold]
    fn grace_passed(&self) -> bool {
        if self.grace == 0 {
            return true;
        }
        let now = self.now();
        let first = match self.seen.compare_exchange(0, now, Relaxed, Relaxed) {
            Ok(_) => now,
            Err(seen) => seen,
        };
        now.saturating_sub(first) >= self.grace
    }

    /// On the hook's thread, counts a poll down (unless `now`) and, when due, calls the
    /// hook; raises the request if it says so. Whether it did.
    fn call(&self, hook: &Hook, now: bool) -> bool {
        if THREAD.with(|t| *t != hook.thread) {
            return false;
        }
        if !now && hook.countdown.fetch_sub(1, Relaxed) > 1 {
            return false;
        }
        hook.countdown.store(HOOK_POLLS, Relaxed);
        let now = self.now();
        let interval = u64::try_from(HOOK_INTERVAL.as_nanos()).unwrap_or(u64::MAX);
        let last = hook.last.load(Relaxed);
        if last != 0 && now.saturating_sub(last) < interval {
            return false;
        }
        let raised = (hook.check)();
        // The interval runs from the hook's return: a hook that waits (Python's, for the
        // interpreter lock another Python thread holds, up to its switch interval) would
        // otherwise be due again at once, and every poll would wait.
        hook.last.store(self.now(), Relaxed);
        if raised {
            self.flag.store(true, Relaxed);
        }
        raised
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn none_never_asks() {
        let c = Cancel::none();
        c.cancel();
        assert!(!c.is_active() && !c.requested() && !c.abandon());
    }

    #[test]
    fn clones_share_the_request() {
        let c = Cancel::new();
        let d = c.clone();
        assert!(!d.requested());
        c.cancel();
        assert!(d.requested() && d.abandon());
    }

    /// A hook that takes longer than the interval (Python's waits for the interpreter
    /// lock) is called at most once per interval of the poller's own work, not at every
    /// poll: calls ≤ 1 + (time outside the hook) / interval.
    #[test]
    fn a_slow_hook_is_not_called_at_every_poll() {
        use std::sync::atomic::AtomicUsize;
        let calls = Arc::new(AtomicUsize::new(0));
        let counted = calls.clone();
        let inside = Arc::new(AtomicU64::new(0));
        let spent = inside.clone();
        let cancel = Cancel::new().with_hook(move || {
            let start = Instant::now();
            std::thread::sleep(HOOK_INTERVAL + Duration::from_millis(10));
            counted.fetch_add(1, Relaxed);
            spent.fetch_add(start.elapsed().as_nanos() as u64, Relaxed);
            false
        });
        let start = Instant::now();
        for _ in 0..40 {
            assert!(!cancel.check());
            let work = Instant::now();
            while work.elapsed() < Duration::from_millis(1) {}
        }
        let outside = start.elapsed().as_nanos() as u64 - inside.load(Relaxed);
        let allowed = 1 + outside / HOOK_INTERVAL.as_nanos() as u64;
        let made = calls.load(Relaxed) as u64;
        assert!(made >= 1, "the first check calls the hook");
        assert!(made <= allowed, "{made} calls, at most {allowed} allowed");
    }

    #[test]
    fn grace_delays_abandoning() {
        let c = Cancel::new().with_grace(Duration::from_millis(50));
        c.cancel();
        assert!(c.requested());
        assert!(!c.abandon(), "the grace starts at the first poll");
        std::thread::sleep(Duration::from_millis(60));
        assert!(c.abandon());
    }

    #[test]
    fn a_flag_set_elsewhere_is_seen() {
        let flag = Arc::new(AtomicBool::new(false));
        let c = Cancel::from_flag(flag.clone());
        assert!(!c.requested());
        flag.store(true, Relaxed);
        assert!(c.requested());
    }

    #[test]
    fn a_hook_raises_the_request() {
        let calls = Arc::new(AtomicU32::new(0));
        let counted = calls.clone();
        let c = Cancel::new().with_hook(move || counted.fetch_add(1, Relaxed) >= 1);
        assert!(!c.requested(), "first poll: the hook says no");
        let start = Instant::now();
        while !c.requested() {
            assert!(
                start.elapsed() < Duration::from_secs(5),
                "hook never raised it"
            );
        }
        assert!(c.abandon());
        assert_eq!(calls.load(Relaxed), 2, "called at most once per interval");
    }

    #[test]
    fn a_hook_runs_only_on_its_thread() {
        let c = Cancel::new().with_hook(|| true);
        let elsewhere = c.clone();
        let seen = std::thread::spawn(move || (0..100).any(|_| elsewhere.check()));
        assert!(
            !seen.join().unwrap_or(true),
            "not raised from another thread"
        );
        assert!(c.check(), "raised on its own");
    }
}
