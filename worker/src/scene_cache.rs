//! The prepared scenes a worker keeps, by job, within a bound on their memory: when a new scene
//! does not fit, the least recently used ones go first (a worker serving many jobs at once keeps
//! the ones it is rendering, and prepares again only a scene it has not used for a while).
//! Jobs of the same content — the same scene, plan and limits, as fifty clients submitting one
//! scene, or a restorer's snapshots of one view — share one prepared scene, counted once.

use std::sync::Arc;

pub struct SceneCache<T> {
    bound_bytes: usize,
    entries: Vec<Entry<T>>,
    clock: u64,
}

struct Entry<T> {
    job: String,
    /// What the scene was prepared from (a hash of the job's scene, plan and limits).
    content: String,
    value: Arc<T>,
    bytes: usize,
    used: u64,
}

impl<T> SceneCache<T> {
    pub fn new(bound_bytes: usize) -> Self {
        Self { bound_bytes, entries: Vec::new(), clock: 0 }
    }

    /// The scene of `job`, marked as just used.
    pub fn get(&mut self, job: &str) -> Option<Arc<T>> {
        self.clock += 1;
        let clock = self.clock;
        self.entries.iter_mut().find(|e| e.job == job).map(|e| {
            e.used = clock;
            e.value.clone()
        })
    }

    /// The scene prepared from `content` for another job, marked as just used.
    pub fn get_by_content(&mut self, content: &str) -> Option<(Arc<T>, usize)> {
        self.clock += 1;
        let clock = self.clock;
        self.entries.iter_mut().find(|e| e.content == content).map(|e| {
            e.used = clock;
            (e.value.clone(), e.bytes)
        })
    }

    /// Keeps `value` (of `bytes`, prepared from `content`) for `job`, evicting the least
    /// recently used scenes until it fits; a scene larger than the bound alone is kept alone.
    /// The jobs evicted.
    pub fn insert(&mut self, job: &str, content: &str, value: Arc<T>, bytes: usize) -> Vec<String> {
        self.entries.retain(|e| e.job != job);
        let shared = self.entries.iter().any(|e| e.content == content);
        let bytes_more = if shared { 0 } else { bytes };
        let mut evicted = Vec::new();
        while !self.entries.is_empty() && self.total() + bytes_more > self.bound_bytes {
            let oldest =
                (0..self.entries.len()).min_by_key(|&i| self.entries[i].used).expect("not empty");
            evicted.push(self.entries.swap_remove(oldest).job);
        }
        self.clock += 1;
        let (job, content) = (job.to_owned(), content.to_owned());
        self.entries.push(Entry { job, content, value, bytes, used: self.clock });
        evicted
    }

    /// The bytes kept: each content's once, however many jobs share it.
    pub fn total(&self) -> usize {
        let mut seen: Vec<&str> = Vec::new();
        let mut total = 0;
        for e in &self.entries {
            if !seen.contains(&e.content.as_str()) {
                seen.push(&e.content);
                total += e.bytes;
            }
        }
        total
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_least_recently_used_scenes_go_first_and_the_bound_holds() {
        let mut cache = SceneCache::new(100);
        for job in ["a", "b", "c", "d", "e"] {
            assert!(cache.insert(job, job, Arc::new(job), 20).is_empty());
        }
        assert_eq!(cache.total(), 100);
        // Using a and c makes b the least recently used, then d.
        assert!(cache.get("a").is_some());
        assert!(cache.get("c").is_some());
        assert_eq!(cache.insert("f", "f", Arc::new("f"), 35), ["b", "d"]);
        assert!(cache.total() <= 100);
        assert!(cache.get("b").is_none() && cache.get("a").is_some());
        // The fifth live job does not empty the cache (the old worker cleared everything).
        assert_eq!(cache.len(), 4);
        // A scene larger than the bound is kept, alone.
        assert_eq!(cache.insert("huge", "huge", Arc::new("huge"), 500).len(), 4);
        assert_eq!((cache.len(), cache.total()), (1, 500));
        assert!(cache.get("huge").is_some());
    }

    #[test]
    fn jobs_of_one_content_share_a_scene_counted_once() {
        let mut cache = SceneCache::new(100);
        let scene = Arc::new("scene");
        assert!(cache.insert("job-1", "content", scene.clone(), 60).is_empty());
        let (found, bytes) = cache.get_by_content("content").unwrap();
        assert!(Arc::ptr_eq(&found, &scene) && bytes == 60);
        // A second job of the same content evicts nothing and adds nothing.
        assert!(cache.insert("job-2", "content", found, bytes).is_empty());
        assert_eq!((cache.len(), cache.total()), (2, 60));
        assert!(cache.get_by_content("other").is_none());
        assert!(cache.get("job-1").is_some() && cache.get("job-2").is_some());
    }
}
