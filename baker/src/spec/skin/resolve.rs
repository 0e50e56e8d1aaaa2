//! The skin resolver's steps over the whole spec: `defaults`, the entry budget of the sweeps,
//! listed and swept entries, the memory floor of the profiles, and one evaluation of every
//! entry's model (what a bake would otherwise reject later).

use super::cx::SkinCx;
use super::merge::merge;
use super::profiles::ProfileSettings;
use super::raw::{RawParams, RawSpec};
use super::sweep::{expand, fill_template, point_count, single_point};
use super::types::{ResolvedEntry, SkinSpec};
use crate::spec::check::{count_text, loc};
use crate::spec::limits::Limits;
use crate::spec::names;
use crate::spec::yaml::Spanned;
use crate::spectral::WavelengthGrid;

impl SkinCx {
    /// The whole spec, every error recorded (in the order a reader meets them).
    pub(super) fn resolve(&mut self, raw: RawSpec) -> SkinSpec {
        self.version(&raw.version);
        let limits = self.limits(raw.limits.as_ref());
        let wavelengths = self.wavelengths(&raw, &limits);
        let defaults = self.defaults(&raw);
        let expand_sweeps = self.sweeps_within_limit(&raw, &defaults, &limits);
        let mut entries = self.listed_entries(&raw, &defaults);
        for s in &raw.sweeps {
            self.swept_entries(s, &defaults, expand_sweeps, &mut entries);
        }
        if raw.entries.is_empty() && raw.sweeps.is_empty() {
            self.invalid((1, 1), "entries", "the spec has no entries and no sweeps");
        }
        self.reject_duplicate_names("name", entries.iter().map(|e| (e.name.as_str(), e.line)));
        let profiles = self.profiles(&raw, &limits);
        // Before any entry is evaluated: could this spec's profiles fit at all?
        self.memory_floor(entries.len(), &wavelengths, &profiles, &limits);
        let mut docs = Vec::new();
        if self.errors.is_empty() {
            docs = self.evaluate(&entries, &wavelengths);
        }
        // Simulation groups (entries sharing scattering), for the bake's cost and memory.
        let plan = crate::profile::plan(&docs, wavelengths.len(), true);
        let groups = plan.groups.len();
        let largest_group = plan.groups.iter().map(Vec::len).max().unwrap_or(0);
        let photons_at = raw
            .profiles
            .as_ref()
            .and_then(|p| p.value.photons.as_ref().map(loc))
            .unwrap_or((1, 1));
        SkinSpec {
            file: self.file.clone(),
            wavelengths,
            entries,
            profiles,
            limits,
            photons_at,
            groups,
            largest_group,
            sha256: String::new(),
            optics: docs,
        }
    }

    /// `defaults:`, checked: no name, no lists.
    fn defaults(&mut self, raw: &RawSpec) -> RawParams {
        let defaults = raw
            .defaults
            .as_ref()
            .map(|d| d.value.clone())
            .unwrap_or_default();
        if let Some(d) = &raw.defaults {
            if let Some(n) = &d.value.name {
                self.invalid(
                    loc(n),
                    "defaults.name",
                    "names belong to entries and sweeps, not defaults",
                );
            }
            self.reject_lists(&d.value, "defaults");
        }
        defaults
    }

    /// Whether the sweeps are expanded: how many entries the spec expands to, counted before
    /// any is built, is within `limits.entries`.
    fn sweeps_within_limit(
        &mut self,
        raw: &RawSpec,
        defaults: &RawParams,
        limits: &Limits,
    ) -> bool {
        let sweep_sizes: Vec<u64> = raw
            .sweeps
            .iter()
            .map(|s| point_count(&merge(defaults, &s.value)))
            .collect();
        let total = sweep_sizes
            .iter()
            .fold(raw.entries.len() as u64, |a, &n| a.saturating_add(n));
        let expand_sweeps = total <= limits.entries;
        if !expand_sweeps {
            let (k, n) = sweep_sizes
                .iter()
                .enumerate()
                .max_by_key(|x| *x.1)
                .map(|(k, n)| (k, *n))
                .unwrap_or((0, 0));
            let at = raw.sweeps.get(k).map_or((1, 1), loc);
            self.over_limit(
                at,
                "sweeps",
                format!(
                    "the spec expands to {} entries ({} from the sweep on line {})",
                    count_text(total),
                    count_text(n),
                    at.0
                ),
                "entries",
                count_text(limits.entries),
            );
        }
        expand_sweeps
    }

    /// The entries of `entries:`, each merged onto `defaults`.
    fn listed_entries(&mut self, raw: &RawSpec, defaults: &RawParams) -> Vec<ResolvedEntry> {
        let mut entries = Vec::new();
        for e in &raw.entries {
            self.reject_lists(&e.value, "entries");
            let merged = merge(defaults, &e.value);
            let Some(name) = merged.name.clone() else {
                self.invalid(loc(e), "name", "every entry needs a name");
                continue;
            };
            if let Err(m) = names::check(&name.value) {
                self.invalid(loc(&name), "name", names::message(&name.value, &m));
                continue;
            }
            let point = single_point(&merged);
            if let Some(params) = self.params(&merged, &point, loc(e)) {
                entries.push(ResolvedEntry {
                    name: name.value.clone(),
                    line: loc(e).0,
                    params,
                });
            }
        }
        entries
    }

    /// The entries of sweep `s` (merged onto `defaults`), appended to `entries` when `expand`;
    /// its template and repeats are checked either way.
    fn swept_entries(
        &mut self,
        s: &Spanned<RawParams>,
        defaults: &RawParams,
        expand_sweeps: bool,
        entries: &mut Vec<ResolvedEntry>,
    ) {
        let merged = merge(defaults, &s.value);
        let Some(template) = merged.name.clone() else {
            self.invalid(
                loc(s),
                "name",
                "every sweep needs a name template, e.g. \"fitz_{skin_type}_{age}\"",
            );
            return;
        };
        self.check_template(&template, &merged);
        self.reject_repeats(&s.value);
        if !expand_sweeps {
            return;
        }
        let mut bad_name = false;
        for point in expand(&merged) {
            let name = fill_template(&template.value, &point);
            if let Err(m) = names::check(&name) {
                // One message per template, for its first bad name.
                if !bad_name {
                    self.invalid(
                        loc(&template),
                        "name",
                        format!(
                            "the template {:?} gives {name:?}, which {m}; allowed: {}",
                            template.value,
                            names::ALLOWED
                        ),
                    );
                }
                bad_name = true;
                continue;
            }
            if let Some(params) = self.params(&merged, &point, loc(s)) {
                entries.push(ResolvedEntry {
                    name,
                    line: loc(s).0,
                    params,
                });
            }
        }
    }

    /// The part of the bake's memory bound that grouping cannot lower
    /// ([`crate::spec::limits::skin_floor_bytes`]), against `limits.memory_gib`.
    fn memory_floor(
        &mut self,
        entries: usize,
        wavelengths: &WavelengthGrid,
        profiles: &ProfileSettings,
        limits: &Limits,
    ) {
        let floor = crate::spec::limits::skin_floor_bytes(
            entries as f64,
            wavelengths.len() as f64,
            crate::transport::RadialBins::fine_then_log_count(
                profiles.dr_min_mm,
                profiles.growth,
                profiles.r_max_mm,
                limits.radial_bins,
            ) as f64,
        );
        if floor > limits.memory_gib * crate::spec::limits::GIB {
            self.over_limit(
                (1, 1),
                "spec",
                format!(
                    "{} entries × {} wavelengths of profiles need {:.1} GiB of memory",
                    count_text(entries as u64),
                    wavelengths.len(),
                    floor / crate::spec::limits::GIB
                ),
                "memory_gib",
                format!("{} GiB", limits.memory_gib),
            );
        }
    }

    /// What the bake would reject after the spec: a layer that vanishes with age, a junction
    /// deeper than its layers, a stack the transport refuses. The layer optics of the entries
    /// that pass.
    fn evaluate(
        &mut self,
        entries: &[ResolvedEntry],
        wavelengths: &WavelengthGrid,
    ) -> Vec<formats::OpticsEntry> {
        let mut docs = Vec::new();
        for e in entries {
            match check_model(e, wavelengths) {
                Ok(d) => docs.push(d),
                Err(m) => self.invalid((e.line, 1), "entry", format!("{}: {m}", e.name)),
            }
        }
        docs
    }
}

/// The checks a bake applies after the spec, run on the entry: the model evaluates (§3.4:
/// layers keep a thickness, the junction fits its layers) and every wavelength's stack is one
/// the transport accepts.
fn check_model(e: &ResolvedEntry, grid: &WavelengthGrid) -> Result<formats::OpticsEntry, String> {
    let o = crate::skin::evaluate(&e.params, grid).map_err(|err| err.to_string())?;
    let doc = crate::skin::document::entry(&e.name, &e.params, &o);
    for (i, lambda_nm) in grid.lambda_nm().iter().enumerate() {
        let stack = crate::transport::stack::from_skin(&doc, i);
        let set: Vec<f64> = doc.layers.iter().map(|l| l.mua_per_mm[i]).collect();
        crate::transport::white::check_sets(&stack, &[set])
            .map_err(|m| format!("at {lambda_nm} nm: {m}"))?;
    }
    Ok(doc)
}
