//! The last few values made, by key: what is costly to make again (a scene's preview, a
//! submission's plan), bounded by count, the oldest going first.

use std::sync::{Mutex, MutexGuard};

pub struct Recent<K, V> {
    capacity: usize,
    kept: Mutex<Vec<(K, V)>>,
}

impl<K: PartialEq, V: Clone> Recent<K, V> {
    /// Keeps at most `capacity` values (at least one).
    pub fn new(capacity: usize) -> Self {
        Recent { capacity: capacity.max(1), kept: Mutex::new(Vec::new()) }
    }

    /// The value kept for `key`.
    pub fn get(&self, key: &K) -> Option<V> {
        self.lock().iter().find(|(k, _)| k == key).map(|(_, v)| v.clone())
    }

    /// Keeps `value` for `key`, in place of what was kept for it; the oldest value goes when
    /// `capacity` are kept.
    pub fn keep(&self, key: K, value: V) {
        let mut kept = self.lock();
        kept.retain(|(k, _)| *k != key);
        if kept.len() == self.capacity {
            kept.remove(0);
        }
        kept.push((key, value));
    }

    fn lock(&self) -> MutexGuard<'_, Vec<(K, V)>> {
        self.kept.lock().unwrap_or_else(|p| p.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_oldest_goes_first_and_a_key_is_kept_once() {
        let recent = Recent::new(2);
        recent.keep("a", 1);
        recent.keep("b", 2);
        recent.keep("a", 3);
        assert_eq!((recent.get(&"a"), recent.get(&"b")), (Some(3), Some(2)));
        recent.keep("c", 4);
        assert_eq!(
            (recent.get(&"b"), recent.get(&"a"), recent.get(&"c")),
            (None, Some(3), Some(4))
        );
    }
}
