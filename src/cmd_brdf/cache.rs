//! The model cache of `lustre brdf eval`: least-recently-used maps of built
//! models and of the full-GHS S̃ tables they share.
//!
//! Keys are exactly what the cached value depends on. A built model embeds
//! its Fresnel term, so its key holds every query parameter including the
//! metal; the S̃ table of full GHS depends only on the correlation shape (γ)
//! and the (u, g) ranges it covers (set by Lc and σ), not on the metal, the
//! energy option or the wavelength, so models that differ only in those
//! share one table build.

use std::collections::{BTreeMap, HashMap};
use std::hash::Hash;
use std::sync::Arc;

use brdf::Bxdf;
use brdf::wave::ghs_table::GhsTable;

/// A map that evicts the least recently used entries beyond a count and a
/// total weight (bytes, as the caller measures them). `get` and `insert`
/// are O(log n).
pub struct Lru<K, V> {
    map: HashMap<K, (V, u64, usize)>,
    /// Use stamp → key, oldest first.
    order: BTreeMap<u64, K>,
    clock: u64,
    max_entries: usize,
    max_weight: usize,
    weight: usize,
}

impl<K: Hash + Eq + Clone, V> Lru<K, V> {
    /// An empty cache holding at most `max_entries` values of total weight
    /// `max_weight` (the most recent value is kept even if heavier).
    pub fn new(max_entries: usize, max_weight: usize) -> Self {
        Lru {
            map: HashMap::new(),
            order: BTreeMap::new(),
            clock: 0,
            max_entries: max_entries.max(1),
            max_weight,
            weight: 0,
        }
    }

    /// The value of `k`, marking it most recently used.
    pub fn get(&mut self, k: &K) -> Option<&V> {
        let (_, stamp, _) = self.map.get_mut(k)?;
        self.order.remove(stamp);
        self.clock += 1;
        *stamp = self.clock;
        self.order.insert(self.clock, k.clone());
        self.map.get(k).map(|e| &e.0)
    }

    /// Inserts (or replaces) `k`, then evicts the least recently used
    /// entries until the limits hold.
    pub fn insert(&mut self, k: K, v: V, weight: usize) {
        if let Some((_, stamp, w)) = self.map.remove(&k) {
            self.order.remove(&stamp);
            self.weight -= w;
        }
        self.clock += 1;
        self.order.insert(self.clock, k.clone());
        self.map.insert(k, (v, self.clock, weight));
        self.weight += weight;
        while self.map.len() > self.max_entries
            || (self.weight > self.max_weight && self.map.len() > 1)
        {
            let Some((_, oldest)) = self.order.pop_first() else {
                break;
            };
            if let Some((_, _, w)) = self.map.remove(&oldest) {
                self.weight -= w;
            }
        }
    }

    /// Entries held.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.map.len()
    }
}

/// Key of a full-GHS S̃ table: the bit patterns of γ, u_max and g_max.
pub type TableKey = (u64, u64, u64);

/// Most models kept: a GHS or two-scale model holds ~20–50 kB of its own
/// tables, so 2048 of them stay below ~100 MB, and a stream over 1000
/// surfaces never rebuilds one.
pub const MODEL_ENTRIES: usize = 2048;
/// Bytes of S̃ tables kept (one is ~0.2–1 MB).
pub const TABLE_BYTES: usize = 256 << 20;

/// Built models and shared tables, with counts of how many were built.
pub struct ModelCache {
    /// Models by their full parameter key.
    pub models: Lru<String, Box<dyn Bxdf>>,
    /// Full-GHS S̃ tables by [`TableKey`].
    pub tables: Lru<TableKey, Arc<GhsTable>>,
    /// GHS-SSA and two-scale models by every parameter but the Fresnel
    /// term, which none of their tables depends on: another metal is a
    /// `with_fresnel` clone, not a rebuild.
    pub surfaces: Lru<String, SurfaceModel>,
    /// A query's material keys as written (canonical JSON) → the key of its model.
    pub resolved: Lru<String, String>,
    /// Models built so far (cache misses).
    pub model_builds: usize,
    /// S̃ tables built so far.
    pub table_builds: usize,
}

/// A model whose tables do not depend on its Fresnel term.
#[derive(Clone)]
pub enum SurfaceModel {
    /// GHS smooth-surface approximation on a KC surface.
    Ssa(Box<brdf::wave::GhsSsa>),
    /// Two-scale.
    TwoScale(Box<brdf::wave::two_scale::TwoScale>),
}

/// Fresnel-free models kept for `with_fresnel` (each holds its tables).
pub const SURFACE_ENTRIES: usize = 256;

impl Default for ModelCache {
    fn default() -> Self {
        ModelCache::with_limits(MODEL_ENTRIES, TABLE_BYTES)
    }
}

impl ModelCache {
    /// A cache with explicit limits (tests use small ones).
    pub fn with_limits(models: usize, table_bytes: usize) -> Self {
        ModelCache {
            models: Lru::new(models, usize::MAX),
            tables: Lru::new(usize::MAX, table_bytes),
            surfaces: Lru::new(SURFACE_ENTRIES, usize::MAX),
            resolved: Lru::new(models.saturating_mul(4), usize::MAX),
            model_builds: 0,
            table_builds: 0,
        }
    }

    /// The S̃ table for `key`, built by `build` on a miss.
    pub fn table<E>(
        &mut self,
        key: TableKey,
        build: impl FnOnce() -> Result<GhsTable, E>,
    ) -> Result<Arc<GhsTable>, E> {
        if let Some(t) = self.tables.get(&key) {
            return Ok(t.clone());
        }
        let t = Arc::new(build()?);
        self.table_builds += 1;
        self.tables.insert(key, t.clone(), t.memory_bytes());
        Ok(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lru_evicts_least_recently_used_by_count_and_weight() {
        let mut c: Lru<u32, u32> = Lru::new(3, 100);
        c.insert(1, 10, 1);
        c.insert(2, 20, 1);
        c.insert(3, 30, 1);
        assert_eq!(c.get(&1), Some(&10)); // 2 is now the oldest
        c.insert(4, 40, 1);
        assert_eq!(c.len(), 3);
        assert!(c.get(&2).is_none());
        assert!(c.get(&1).is_some() && c.get(&3).is_some() && c.get(&4).is_some());
        // Weight: a heavy entry pushes out the oldest until the total fits.
        c.insert(5, 50, 100);
        assert!(c.get(&5).is_some());
        assert_eq!(c.len(), 1, "only the newest fits under weight 100");
        // Replacing a key keeps one entry and its new weight.
        c.insert(5, 51, 2);
        c.insert(6, 60, 2);
        assert_eq!(c.get(&5), Some(&51));
        assert_eq!(c.len(), 2);
    }
}
