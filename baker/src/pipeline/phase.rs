//! The phase of a bake that is running (skin simulation, skin fits, one fiber entry's
//! tracing): how many of its units are done, its photons, and the bar or periodic lines
//! people see. [`super::Runner::unit`] reports every counted unit here, and the JSON unit
//! events carry the phase's counts.

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use super::events::{Bar, Events, Place};
use crate::progress::{duration, si};

/// What a phase is made of, declared when it starts.
#[derive(Debug, Clone)]
pub struct PhaseSpec {
    /// `simulation`, `fitting` or `tracing`.
    pub name: String,
    /// Shown before the counts (`simulation`, `fitting`, a fiber entry's name).
    pub label: String,
    /// Units of the phase (cached ones included).
    pub units: u64,
    /// Expected photons of each unit (0 for fits); a unit's real count replaces it once
    /// the unit starts or comes from the cache.
    pub photons_per_unit: u64,
    /// What the bar counts and its rate shows: photons per item (1: photons; a fiber's
    /// photons per direction: directions), or `None` for one item per unit (profiles).
    pub photons_per_item: Option<u64>,
    /// The items' name: `photons`, `directions`, `profiles`.
    pub item: String,
}

/// The counts of the running phase.
pub struct Phase {
    spec: PhaseSpec,
    t0: Instant,
    started: AtomicU64,
    done: AtomicU64,
    /// Units seen (started or cached), their photons, and the photons of those computed.
    seen: AtomicU64,
    photons_seen: AtomicU64,
    photons_done: AtomicU64,
    /// Items the physics reported (photons traced, directions) and items still to trace.
    items_done: AtomicU64,
    items_cached: AtomicU64,
    bar: Option<Arc<dyn Bar>>,
    /// Units done at the last periodic line.
    last_line: Mutex<u64>,
    events: Events,
}

impl std::fmt::Debug for Phase {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Phase({})", self.spec.name)
    }
}

impl Phase {
    /// Starts phase `spec`: emits `phase_started` and draws a bar where one can be drawn.
    pub fn start(spec: PhaseSpec, events: &Events) -> Arc<Phase> {
        events.emit(
            serde_json::json!({"event": "phase_started", "phase": spec.name,
            "label": spec.label, "units": spec.units,
            "photons_total": spec.units * spec.photons_per_unit}),
        );
        let p = Phase {
            bar: None,
            t0: Instant::now(),
            started: 0.into(),
            done: 0.into(),
            seen: 0.into(),
            photons_seen: 0.into(),
            photons_done: 0.into(),
            items_done: 0.into(),
            items_cached: 0.into(),
            last_line: Mutex::new(0),
            events: events.clone(),
            spec,
        };
        let bar = events.bar(p.items_total(), &p.spec.label, &p.spec.item);
        let p = Arc::new(Phase { bar, ..p });
        p.show();
        p
    }

    /// Photons of the phase: those of the units seen, and the expected count of the rest.
    pub fn photons_total(&self) -> u64 {
        let unseen = self.spec.units.saturating_sub(self.seen.load(Relaxed));
        self.photons_seen.load(Relaxed) + unseen * self.spec.photons_per_unit
    }

    /// Items the bar counts to: all but those of cached units.
    fn items_total(&self) -> u64 {
        let all = match self.spec.photons_per_item {
            Some(per) => self.photons_total() / per.max(1),
            None => self.spec.units,
        };
        all.saturating_sub(self.items_cached.load(Relaxed))
    }

    fn items(&self, photons: u64) -> u64 {
        match self.spec.photons_per_item {
            Some(per) => photons / per.max(1),
            None => 1,
        }
    }

    fn place(&self, index: u64) -> Place {
        Place {
            phase: self.spec.name.clone(),
            index,
            total: self.spec.units,
            photons_done: self.photons_done.load(Relaxed),
            photons_total: self.photons_total(),
        }
    }

    /// A unit of `photons` starts computing; its place (index: the how-manieth start).
    pub fn unit_started(&self, photons: u64) -> Place {
        self.seen.fetch_add(1, Relaxed);
        self.photons_seen.fetch_add(photons, Relaxed);
        let i = self.started.fetch_add(1, Relaxed) + 1;
        if let Some(b) = &self.bar {
            b.set_length(self.items_total());
        }
        self.place(i)
    }

    /// A unit of `photons` is done (computed, or from the cache when `cached`); its place
    /// (index: the how-manieth done).
    pub fn unit_done(&self, photons: u64, cached: bool) -> Place {
        if cached {
            self.seen.fetch_add(1, Relaxed);
            self.photons_seen.fetch_add(photons, Relaxed);
            self.items_cached.fetch_add(self.items(photons), Relaxed);
        } else if self.spec.photons_per_item.is_none() {
            self.advance_items(1);
        }
        self.photons_done.fetch_add(photons, Relaxed);
        let i = self.done.fetch_add(1, Relaxed) + 1;
        if let Some(b) = &self.bar {
            b.set_length(self.items_total());
        }
        self.show();
        self.place(i)
    }

    fn advance_items(&self, n: u64) {
        self.items_done.fetch_add(n, Relaxed);
        if let Some(b) = &self.bar {
            b.advance(n);
        }
    }

    /// The bar's message, or a periodic line (every ~5 % of the units) without a bar.
    fn show(&self) {
        let done = self.done.load(Relaxed);
        let total = self.spec.units;
        let what = match self.spec.photons_per_item {
            Some(_) => "units",
            None => self.spec.item.as_str(),
        };
        let counts = format!("{} {done}/{total} {what}", self.spec.label);
        if let Some(b) = &self.bar {
            b.set_message(&counts);
            return;
        }
        if !self.events.human() || done == 0 {
            return;
        }
        let step = (total / 20).max(1);
        let mut last = self.last_line.lock().unwrap();
        if done < *last + step && done != total {
            return;
        }
        *last = done;
        let el = self.t0.elapsed().as_secs_f64();
        let items = self.items_done.load(Relaxed);
        let rate = items as f64 / el.max(1e-9);
        let left = self.items_total().saturating_sub(items);
        let eta = if rate > 0.0 { left as f64 / rate } else { 0.0 };
        self.events.say(format!(
            "  {counts}, {}, {} elapsed, eta {}",
            si(rate, &format!("{}/s", self.spec.item)),
            duration(el),
            duration(eta)
        ));
    }

    /// Clears the bar and emits `phase_finished`.
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish();
        }
        self.events
            .emit(serde_json::json!({"event": "phase_finished",
            "phase": self.spec.name, "label": self.spec.label,
            "units": self.done.load(Relaxed), "photons": self.photons_done.load(Relaxed),
            "seconds": self.t0.elapsed().as_secs_f64()}));
    }
}

impl crate::progress::Progress for Phase {
    /// The physics finished `n` items (photons, directions).
    fn advance(&self, n: u64) {
        self.advance_items(n);
    }
}
