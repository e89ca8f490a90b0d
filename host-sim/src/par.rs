//! Independent jobs on every core: the corpus test and `cargo xtask fuzz`
//! run jobs of very different lengths, so each worker takes the next job
//! as it frees (a fixed split would leave a core idle behind a long one).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// `f(i)` for every index in `order` (a permutation of `0..order.len()`,
/// the order the jobs start in), on one thread per core; the results by
/// index. A job that panics fails the call once every worker has stopped.
pub fn each_core<R: Send>(order: &[usize], f: impl Fn(usize) -> R + Sync) -> Vec<R> {
    let next = AtomicUsize::new(0);
    let done = Mutex::new(Vec::with_capacity(order.len()));
    let width = std::thread::available_parallelism().map_or(1, |n| n.get());
    std::thread::scope(|s| {
        for _ in 0..width.min(order.len()) {
            s.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some(&i) = order.get(k) else { break };
                let r = f(i);
                done.lock().unwrap_or_else(|e| e.into_inner()).push((i, r));
            });
        }
    });
    let mut done = done.into_inner().unwrap_or_else(|e| e.into_inner());
    done.sort_by_key(|d| d.0);
    done.into_iter().map(|d| d.1).collect()
}

#[cfg(test)]
mod tests {
    /// Every index runs once and the results come back in index order,
    /// whatever order they started and finished in.
    #[test]
    fn each_index_once_in_index_order() {
        let order = [3, 0, 4, 1, 2];
        let out = super::each_core(&order, |i| {
            std::thread::sleep(std::time::Duration::from_millis(5 * (5 - i as u64)));
            i * 10
        });
        assert_eq!(out, vec![0, 10, 20, 30, 40]);
    }
}
