//! The net under third-party parsers: a panic inside one becomes an error the caller words
//! (naming the file), and its message never reaches the user's terminal.
//!
//! Why both halves: `catch_unwind` alone stops the unwinding, but the panic hook has already
//! printed `thread '…' panicked at …` with the parser's internals to stderr by then. So the first
//! [`catch`] installs, once per process, a hook that stays silent while the panicking thread is
//! inside a guarded call (a thread-local depth, set and reset by [`catch`]) and hands every other
//! panic to the hook that was there before, so real defects elsewhere still print as usual.
//!
//! The net is the last line, not the fix: every reader first checks what its parser is known to
//! choke on (counts against the file size, component types, strides) and refuses with a proper
//! message. A panic caught here is a defect to fix in that validation, so [`panics_caught`]
//! counts them, and the fuzz harness (`tests/tests/fuzz_readers.rs`) fails when the count moves.
//!
//! The parser must run on the calling thread: a panic on a thread the parser spawns is not
//! inside the guard (restauro's EXR reader therefore decodes on the calling thread).

use std::cell::Cell;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, Once};

/// A guarded call panicked; the caller turns this into an error that names the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Panicked;

thread_local! {
    /// How many guarded calls this thread is inside (they may nest).
    static DEPTH: Cell<u32> = const { Cell::new(0) };
}

static HOOK: Once = Once::new();
static CAUGHT: AtomicU64 = AtomicU64::new(0);
/// Where the last guarded panic happened and what it said: kept for tests, never printed.
static LAST: Mutex<Option<String>> = Mutex::new(None);

fn install_hook() {
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if DEPTH.with(Cell::get) == 0 {
                previous(info);
                return;
            }
            let payload = info
                .payload()
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| info.payload().downcast_ref::<String>().cloned())
                .unwrap_or_default();
            let location = info.location().map(ToString::to_string).unwrap_or_default();
            if let Ok(mut last) = LAST.lock() {
                *last = Some(format!("{location}: {payload}"));
            }
        }));
    });
}

/// Leaves the guarded scope however the call ends (returning or unwinding).
struct Scope;

impl Scope {
    fn enter() -> Self {
        DEPTH.with(|d| d.set(d.get() + 1));
        Scope
    }
}

impl Drop for Scope {
    fn drop(&mut self) {
        DEPTH.with(|d| d.set(d.get().saturating_sub(1)));
    }
}

/// Run `f` (a call into a third-party parser); a panic inside it is returned as [`Panicked`]
/// without printing anything.
///
/// `f` is treated as unwind-safe: what it touches is the parser's own state and the input,
/// both dropped by the caller on `Err`.
pub fn catch<T>(f: impl FnOnce() -> T) -> Result<T, Panicked> {
    install_hook();
    let result = {
        let _scope = Scope::enter();
        catch_unwind(AssertUnwindSafe(f))
    };
    result.map_err(|_| {
        CAUGHT.fetch_add(1, Ordering::Relaxed);
        Panicked
    })
}

/// How many panics [`catch`] has turned into errors in this process: each is a defect in the
/// validation before a parser, which tests watch for.
pub fn panics_caught() -> u64 {
    CAUGHT.load(Ordering::Relaxed)
}

/// Where the last panic the guard caught happened and its message, for a test to report
/// (users never see it).
pub fn last_caught_panic() -> Option<String> {
    LAST.lock().ok().and_then(|last| last.clone())
}

/// The words for a parser that gave up on a file: what happened and what to do. The parser's
/// own panic message is not shown (it describes the parser, not the file).
pub fn gave_up(format: &str) -> String {
    format!(
        "the {format} reader failed on this file, which is malformed in a way restauro does not \
         recognise; check the file with another {format} tool, or re-export it"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_an_error_and_is_counted() {
        let before = panics_caught();
        let r: Result<(), Panicked> = catch(|| panic!("inside the parser"));
        assert_eq!(r, Err(Panicked));
        assert!(panics_caught() > before);
        assert!(
            last_caught_panic().is_some_and(|p| p.contains("guard.rs")),
            "{:?}",
            last_caught_panic()
        );
        assert_eq!(catch(|| 7), Ok(7));
        // The scope is left on unwinding: a later panic outside a guard is not hidden.
        assert_eq!(DEPTH.with(Cell::get), 0);
        let outside = std::panic::catch_unwind(|| {
            assert_eq!(DEPTH.with(Cell::get), 0);
        });
        assert!(outside.is_ok());
    }

    #[test]
    fn guards_nest() {
        let r = catch(|| {
            let inner: Result<(), Panicked> = catch(|| panic!("inner"));
            assert_eq!(DEPTH.with(Cell::get), 1);
            inner
        });
        assert_eq!(r, Ok(Err(Panicked)));
        assert_eq!(DEPTH.with(Cell::get), 0);
    }
}
