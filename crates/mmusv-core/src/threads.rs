//! Thread pools that survive `fork()`.
//!
//! A forked child process holds a copy of its parent's memory but only the thread that called `fork()`: rayon's
//! global pool, built in the parent, has no threads in the child, and the first parallel call there waits for
//! them forever. That is how a Python user meets it: a PyTorch `DataLoader` with `num_workers > 0` (fork is
//! Linux's default start method) over a dataset that captures frames, after the parent captured one.
//!
//! [`set_owner`] records the process that loaded the library (the Python extension calls it when imported).
//! [`run`] runs parallel work as before in that process (on rayon's global pool: nothing changes there), and in
//! any other process, a child forked from it, inside a pool of that child's own, made on first use
//! ([`ThreadPool::install`]): every `par_iter` within then runs on threads that exist. [`per_process`] gives a
//! named pool (the recorder's encoders) made again in each process that uses it. The work and its results are
//! the same on any pool: no output depends on the number of threads.

use rayon::ThreadPool;
use std::sync::{Arc, Mutex, OnceLock};

/// The process that loaded the library ([`set_owner`]).
static OWNER: OnceLock<u32> = OnceLock::new();

/// The pool of a process other than the owner: its id and the pool.
static CHILD_POOL: Mutex<Option<(u32, Arc<ThreadPool>)>> = Mutex::new(None);

/// Records the calling process as the one whose parallel work runs on rayon's global pool (the first call wins;
/// later calls, in the same process or in a forked child, change nothing).
pub fn set_owner() {
    let _ = OWNER.get_or_init(std::process::id);
}

/// Whether this process is not the one [`set_owner`] recorded: a child forked from it.
pub fn forked() -> bool {
    OWNER.get().is_some_and(|&pid| pid != std::process::id())
}

/// Runs `f`: directly in the owner process (or where no owner was recorded), inside this process's own pool in
/// a forked child (see the module docstring). Where the child cannot start a thread, `f` runs directly.
pub fn run<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    if !forked() {
        return f();
    }
    let pool = {
        let mut slot = CHILD_POOL.lock().unwrap_or_else(|e| e.into_inner());
        pool_of_this_process(&mut slot, || rayon::ThreadPoolBuilder::new().thread_name(|i| format!("mmusv-{i}")))
    };
    match pool {
        Some(pool) => pool.install(f),
        None => f(),
    }
}

/// A pool for one purpose, made by `build` in each process that uses it (the parent's copy in a forked child is
/// left alone: its threads are not there). `None` where no thread could be started.
pub fn per_process(
    slot: &Mutex<Option<(u32, Arc<ThreadPool>)>>,
    build: impl FnOnce() -> rayon::ThreadPoolBuilder,
) -> Option<Arc<ThreadPool>> {
    let mut slot = slot.lock().unwrap_or_else(|e| e.into_inner());
    pool_of_this_process(&mut slot, build)
}

fn pool_of_this_process(
    slot: &mut Option<(u32, Arc<ThreadPool>)>,
    build: impl FnOnce() -> rayon::ThreadPoolBuilder,
) -> Option<Arc<ThreadPool>> {
    let pid = std::process::id();
    match slot {
        Some((owner, pool)) if *owner == pid => return Some(pool.clone()),
        // Another process's pool (the parent's, copied by fork): never dropped, since dropping a pool tells its
        // threads to stop, and they are not in this process.
        Some(_) => std::mem::forget(slot.take()),
        None => {}
    }
    let pool = Arc::new(build().build().ok()?);
    *slot = Some((pid, pool.clone()));
    Some(pool)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    #[test]
    fn run_gives_the_same_result_as_the_work_itself() {
        set_owner();
        assert!(!forked());
        let sum: u64 = run(|| (0..10_000u64).into_par_iter().map(|x| x * x).sum());
        assert_eq!(sum, (0..10_000u64).map(|x| x * x).sum());
    }

    #[test]
    fn a_pool_per_process_is_made_once_and_kept() {
        static SLOT: Mutex<Option<(u32, Arc<ThreadPool>)>> = Mutex::new(None);
        let a = per_process(&SLOT, || rayon::ThreadPoolBuilder::new().num_threads(2));
        let b = per_process(&SLOT, || rayon::ThreadPoolBuilder::new().num_threads(3));
        let (Some(a), Some(b)) = (a, b) else { unreachable!("no thread could be started") };
        assert!(Arc::ptr_eq(&a, &b) && a.current_num_threads() == 2);
        // a slot holding another process's pool (as after fork) gets a new one
        *SLOT.lock().unwrap_or_else(|e| e.into_inner()) = Some((u32::MAX, a.clone()));
        let Some(c) = per_process(&SLOT, || rayon::ThreadPoolBuilder::new().num_threads(3)) else {
            unreachable!("no thread could be started")
        };
        assert!(!Arc::ptr_eq(&a, &c) && c.current_num_threads() == 3);
    }
}
