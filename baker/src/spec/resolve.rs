//! From the raw spec to validated model inputs: defaults merged, sweeps expanded, every value
//! range-checked with its location, units applied.

use std::collections::HashMap;
use std::path::Path;

use super::error::{num, SpecError, SpecErrors};
use super::limits::{count_text, Limits};
use super::raw::{OneOrMany, RawCollagen, RawLayerValues, RawParams, RawSpec, Spanned, Token};
use super::{names, syntax};
use crate::skin::params::{CollagenAging, SkewNormal};
use crate::skin::{
    BodyLocation, Freeze, Gender, HypodermisAbsorption, Layer, MelaninInput, ModelKind,
    PheomelaninAbsorption, SkinParams, SkinType, SkinTypeMelanin,
};
use crate::spectral::WavelengthGrid;

/// Age range the model accepts, years: from young adults (the model's base values are adult,
/// §3.4) to 90 (Eq. 4's linear decline stays positive: 1 − 6·(0.06 + 0.10) = 0.04).
pub const AGE_RANGE_YEARS: (f64, f64) = (18.0, 90.0);
/// Wavelengths the embedded spectra cover, nm.
pub const LAMBDA_RANGE_NM: (f64, f64) = (380.0, 780.0);

/// A validated skin spec.
#[derive(Debug, Clone)]
pub struct SkinSpec {
    pub file: String,
    pub wavelengths: WavelengthGrid,
    pub entries: Vec<ResolvedEntry>,
    pub profiles: ProfileSettings,
    pub limits: Limits,
    /// Where `profiles.photons` is set (line 1 when it is not): budget errors point there.
    pub photons_at: (u64, u64),
    /// Simulation groups of entries that share scattering ([`crate::profile::plan`] with
    /// absorption reuse), and the largest group's size.
    pub groups: usize,
    pub largest_group: usize,
    /// SHA-256 of the spec text as read (provenance in every table).
    pub sha256: String,
    /// The layer optics of every entry (in `entries` order), evaluated once by the resolver.
    pub optics: Vec<formats::OpticsEntry>,
}

/// How the diffusion profiles of a spec are baked (`profiles:` block).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ProfileSettings {
    /// Photon packets per wavelength of each shared simulation.
    pub photons: u64,
    pub seed: u64,
    /// Gaussians in the sum-of-Gaussians fit (6 for real-time renderers).
    pub gaussians: usize,
    /// Cheap wavelengths get up to this many times `photons` ([`crate::profile::SimOptions`]).
    pub max_photon_boost: u64,
    /// Radial grid: bins of `dr_min_mm`, then each `growth` times wider, up to `r_max_mm`.
    pub dr_min_mm: f64,
    pub growth: f64,
    pub r_max_mm: f64,
}

impl Default for ProfileSettings {
    /// Photon count: ≤ 1 % relative standard error of every RGB profile bin out to 2 mm (and
    /// within the channel's 99 % radius) on the default database (measured; README
    /// "Diffusion profiles"). Grid: 10 µm core, 5 % growth, 40 mm —
    /// past the red 99 % radius of the most translucent entry.
    fn default() -> Self {
        Self {
            photons: DEFAULT_PROFILE_PHOTONS,
            seed: 1,
            gaussians: 6,
            max_photon_boost: 1,
            dr_min_mm: 0.01,
            growth: 1.05,
            r_max_mm: 40.0,
        }
    }
}

/// Default photons per wavelength and shared simulation.
pub const DEFAULT_PROFILE_PHOTONS: u64 = 4_000_000;

/// One concrete entry (a listed entry, or one point of a sweep).
#[derive(Debug, Clone)]
pub struct ResolvedEntry {
    pub name: String,
    /// Line of the entry or sweep in the spec.
    pub line: u64,
    pub params: SkinParams,
}

/// Reads and validates the skin spec at `path` (a fiber spec is an error that says so).
pub fn load(path: &Path) -> Result<SkinSpec, SpecErrors> {
    match super::load_as(path, super::SpecKind::Skin)? {
        super::Spec::Skin(s) => Ok(s),
        super::Spec::Fiber(_) => unreachable!("load_as checked the kind"),
    }
}

/// Validates spec text; `file` names it in messages.
pub fn load_str(file: &str, text: &str) -> Result<SkinSpec, SpecErrors> {
    let raw: RawSpec = parse_yaml(file, text, &|t| check_str(file, t))?;
    resolve_raw(file, raw).map(|s| SkinSpec {
        sha256: super::sha256_hex(text.as_bytes()),
        ..s
    })
}

fn resolve_raw(file: &str, raw: RawSpec) -> Result<SkinSpec, SpecErrors> {
    let mut cx = Ctx {
        file: file.to_string(),
        ..Ctx::default()
    };
    let spec = cx.resolve(raw);
    cx.dedup();
    if cx.errors.is_empty() {
        Ok(spec)
    } else {
        Err(SpecErrors(cx.errors))
    }
}

/// Every error of spec text, parse errors undiagnosed ([`syntax::Check`]).
fn check_str(file: &str, text: &str) -> Vec<SpecError> {
    match parse_plain::<RawSpec>(file, text) {
        Ok(raw) => resolve_raw(file, raw).err().map_or_else(Vec::new, |e| e.0),
        Err(e) => vec![e],
    }
}

/// Parses spec text into its raw serde form. A syntax or type error names file:line:column,
/// the field and, where it can be found, what the field allows ([`syntax::diagnose`]);
/// `check` validates probed copies of the text for that.
pub(super) fn parse_yaml<T: serde::de::DeserializeOwned>(
    file: &str,
    text: &str,
    check: syntax::Check,
) -> Result<T, SpecErrors> {
    parse_plain(file, text).map_err(|e| {
        let SpecError::Syntax {
            line,
            column,
            message,
            ..
        } = e
        else {
            return SpecErrors(vec![e]);
        };
        let d = syntax::diagnose(text, line, column, &message, check);
        SpecErrors(vec![SpecError::Syntax {
            file: file.to_string(),
            line: d.line,
            column: d.column,
            message: d.message,
        }])
    })
}

/// How specs are parsed: serde-saphyr's budgets (nodes, aliases, depth: an alias bomb or a
/// deeply nested document is an error, not an exhausted machine), and explicit tags it does
/// not know (`!!python/object`) rejected rather than ignored.
pub(super) fn yaml_options() -> serde_saphyr::Options {
    serde_saphyr::options! {
        reject_unsupported_tags: true,
    }
}

/// serde-saphyr's error as it comes, at its line and column.
pub(super) fn parse_plain<T: serde::de::DeserializeOwned>(
    file: &str,
    text: &str,
) -> Result<T, SpecError> {
    serde_saphyr::from_str_with_options(text, yaml_options()).map_err(|e| {
        let (line, column) = e
            .location()
            .map(|l| (l.line(), l.column()))
            .unwrap_or((0, 0));
        SpecError::Syntax {
            file: file.to_string(),
            line,
            column,
            message: e.to_string(),
        }
    })
}

#[derive(Default)]
pub(super) struct Ctx {
    pub(super) file: String,
    pub(super) errors: Vec<SpecError>,
    /// Sections read from files, by file and reading options: a file named by many fibers is
    /// read and checked once.
    pub(super) read_sections: HashMap<String, Result<crate::fiber::Section, String>>,
}

pub(super) fn loc<T>(s: &Spanned<T>) -> (u64, u64) {
    (s.referenced.line(), s.referenced.column())
}

/// One point of a sweep: each sweepable field with the location it came from.
#[derive(Clone, Default)]
struct Point {
    age: Option<Spanned<f64>>,
    gender: Option<Spanned<String>>,
    skin_type: Option<Spanned<Token>>,
    melanosome_fraction: Option<Spanned<f64>>,
    location: Option<Spanned<String>>,
    xi: Option<Spanned<f64>>,
    model: Option<Spanned<String>>,
}

impl Ctx {
    /// Drops repeats of an error (one per point of a sweep), keeping the first of each.
    pub(super) fn dedup(&mut self) {
        let mut seen = Vec::new();
        self.errors.retain(|e| {
            let new = !seen.contains(e);
            if new {
                seen.push(e.clone());
            }
            new
        });
    }

    pub(super) fn invalid(&mut self, at: (u64, u64), field: &str, message: impl Into<String>) {
        self.errors.push(SpecError::Invalid {
            file: self.file.clone(),
            line: at.0,
            column: at.1,
            field: field.to_string(),
            message: message.into(),
        });
    }

    pub(super) fn out_of_range(
        &mut self,
        at: (u64, u64),
        field: &str,
        value: String,
        allowed: String,
    ) {
        self.errors.push(SpecError::OutOfRange {
            file: self.file.clone(),
            line: at.0,
            column: at.1,
            field: field.to_string(),
            value,
            allowed,
        });
    }

    /// `v` within [lo, hi] (`open_lo`: lo excluded); records an error otherwise.
    pub(super) fn in_range(
        &mut self,
        field: &str,
        v: &Spanned<f64>,
        lo: f64,
        hi: f64,
        open_lo: bool,
    ) -> Option<f64> {
        let x = v.value;
        let ok = x.is_finite() && (if open_lo { x > lo } else { x >= lo }) && x <= hi;
        if ok {
            Some(x)
        } else {
            let allowed = format!(
                "{}{}, {}]",
                if open_lo { "(" } else { "[" },
                num(lo),
                num(hi)
            );
            self.out_of_range(loc(v), field, num(x), allowed);
            None
        }
    }

    pub(super) fn opt_range(
        &mut self,
        field: &str,
        v: &Option<Spanned<f64>>,
        lo: f64,
        hi: f64,
        open_lo: bool,
        default: f64,
    ) -> f64 {
        match v {
            Some(s) => self.in_range(field, s, lo, hi, open_lo).unwrap_or(default),
            None => default,
        }
    }

    pub(super) fn choice<T: Copy>(
        &mut self,
        field: &str,
        v: &Spanned<String>,
        options: &[(&str, T)],
    ) -> Option<T> {
        if let Some((_, t)) = options.iter().find(|(k, _)| *k == v.value) {
            return Some(*t);
        }
        let allowed: Vec<&str> = options.iter().map(|o| o.0).collect();
        self.out_of_range(
            loc(v),
            field,
            format!("{:?}", v.value),
            format!("one of {}", allowed.join(", ")),
        );
        None
    }

    fn resolve(&mut self, raw: RawSpec) -> SkinSpec {
        if let Some(v) = &raw.version {
            if v.value != 1 {
                self.out_of_range(loc(v), "version", v.value.to_string(), "1".into());
            }
        }
        let limits = self.limits(raw.limits.as_ref());
        let wavelengths = self.wavelengths(&raw, &limits);
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
        // How many entries the sweeps expand to, counted before any is built.
        let sweep_sizes: Vec<u64> = raw
            .sweeps
            .iter()
            .map(|s| point_count(&merge(&defaults, &s.value)))
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
        let mut entries = Vec::new();
        for e in &raw.entries {
            self.reject_lists(&e.value, "entries");
            let merged = merge(&defaults, &e.value);
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
        for s in &raw.sweeps {
            let merged = merge(&defaults, &s.value);
            let Some(template) = merged.name.clone() else {
                self.invalid(
                    loc(s),
                    "name",
                    "every sweep needs a name template, e.g. \"fitz_{skin_type}_{age}\"",
                );
                continue;
            };
            self.check_template(&template, &merged);
            self.reject_repeats(&s.value);
            if !expand_sweeps {
                continue;
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
        if raw.entries.is_empty() && raw.sweeps.is_empty() {
            self.invalid((1, 1), "entries", "the spec has no entries and no sweeps");
        }
        self.reject_duplicate_names("name", entries.iter().map(|e| (e.name.as_str(), e.line)));
        let profiles = self.profiles(&raw, &limits);
        // What the bake would reject after the spec: a layer that vanishes with age, a junction
        // deeper than its layers, a stack the transport refuses.
        // Before any entry is evaluated: could this spec's profiles fit at all?
        let floor = super::budget::skin_floor_bytes(
            entries.len() as f64,
            wavelengths.len() as f64,
            crate::transport::RadialBins::fine_then_log_count(
                profiles.dr_min_mm,
                profiles.growth,
                profiles.r_max_mm,
                limits.radial_bins,
            ) as f64,
        );
        if floor > limits.memory_gib * super::budget::GIB {
            self.over_limit(
                (1, 1),
                "spec",
                format!(
                    "{} entries × {} wavelengths of profiles need {:.1} GiB of memory",
                    count_text(entries.len() as u64),
                    wavelengths.len(),
                    floor / super::budget::GIB
                ),
                "memory_gib",
                format!("{} GiB", limits.memory_gib),
            );
        }
        let mut docs = Vec::new();
        if self.errors.is_empty() {
            for e in &entries {
                match check_model(e, &wavelengths) {
                    Ok(d) => docs.push(d),
                    Err(m) => self.invalid((e.line, 1), "entry", format!("{}: {m}", e.name)),
                }
            }
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

    /// Two entries with one name, or names equal but for case (one file on macOS and
    /// Windows file systems).
    pub(super) fn reject_duplicate_names<'a>(
        &mut self,
        field: &str,
        names: impl Iterator<Item = (&'a str, u64)>,
    ) {
        let mut seen: HashMap<String, (&'a str, u64)> = HashMap::new();
        let mut dups = Vec::new();
        for (name, line) in names {
            let key = name.to_ascii_lowercase();
            if let Some(&(first, first_line)) = seen.get(&key) {
                dups.push(((line, 1), duplicate_message(name, first, first_line)));
            } else {
                seen.insert(key, (name, line));
            }
        }
        for (at, m) in dups {
            self.invalid(at, field, m);
        }
    }

    fn profiles(&mut self, raw: &RawSpec, limits: &Limits) -> ProfileSettings {
        let mut s = ProfileSettings::default();
        let Some(p) = &raw.profiles else {
            return s;
        };
        let p = &p.value;
        let count = |this: &mut Self, field: &str, v: &Option<Spanned<f64>>, lo: f64, hi: f64| {
            let v = v.as_ref()?;
            let x = this.in_range(field, v, lo, hi, false)?;
            if x.fract() != 0.0 {
                this.invalid(loc(v), field, format!("{x} is not a whole number"));
                return None;
            }
            Some(x as u64)
        };
        if let Some(n) = count(self, "profiles.photons", &p.photons, 1.0, 1e12) {
            s.photons = n;
        }
        if let Some(n) = count(
            self,
            "profiles.seed",
            &p.seed,
            0.0,
            9.007_199_254_740_992e15,
        ) {
            s.seed = n;
        }
        if let Some(n) = count(self, "profiles.gaussians", &p.gaussians, 1.0, 16.0) {
            s.gaussians = n as usize;
        }
        if let Some(n) = count(
            self,
            "profiles.max_photon_boost",
            &p.max_photon_boost,
            1.0,
            64.0,
        ) {
            s.max_photon_boost = n;
        }
        if let Some(r) = &p.radial {
            let radial_at = loc(r);
            let r = &r.value;
            s.dr_min_mm = self.opt_range(
                "profiles.radial.dr_min_mm",
                &r.dr_min_mm,
                0.0,
                1.0,
                true,
                s.dr_min_mm,
            );
            s.growth = self.opt_range(
                "profiles.radial.growth",
                &r.growth,
                1.001,
                2.0,
                false,
                s.growth,
            );
            s.r_max_mm = self.opt_range(
                "profiles.radial.r_max_mm",
                &r.r_max_mm,
                0.0,
                1000.0,
                true,
                s.r_max_mm,
            );
            if s.r_max_mm <= s.dr_min_mm {
                let at = r.r_max_mm.as_ref().map(loc).unwrap_or(radial_at);
                self.invalid(
                    at,
                    "profiles.radial.r_max_mm",
                    format!("must exceed dr_min_mm = {}", s.dr_min_mm),
                );
                s.r_max_mm = 40.0;
            }
            // The bins the grid will have, counted (and capped) before any is allocated.
            let cap = limits.radial_bins;
            let n = crate::transport::RadialBins::fine_then_log_count(
                s.dr_min_mm,
                s.growth,
                s.r_max_mm,
                cap,
            );
            if n > cap {
                let at = r
                    .dr_min_mm
                    .as_ref()
                    .or(r.growth.as_ref())
                    .or(r.r_max_mm.as_ref())
                    .map_or(radial_at, loc);
                self.over_limit(
                    at,
                    "profiles.radial",
                    format!(
                        "dr_min_mm = {}, growth = {}, r_max_mm = {} give more than {} radial bins",
                        num(s.dr_min_mm),
                        num(s.growth),
                        num(s.r_max_mm),
                        count_text(cap)
                    ),
                    "radial_bins",
                    count_text(cap),
                );
                let d = ProfileSettings::default();
                (s.dr_min_mm, s.growth, s.r_max_mm) = (d.dr_min_mm, d.growth, d.r_max_mm);
            }
        }
        s
    }

    fn wavelengths(&mut self, raw: &RawSpec, limits: &Limits) -> WavelengthGrid {
        let Some(w) = &raw.wavelengths else {
            return WavelengthGrid::thesis_default();
        };
        let (lo, hi) = LAMBDA_RANGE_NM;
        let v = &w.value;
        if let Some(list) = &v.list_nm {
            let range = [&v.start_nm, &v.stop_nm, &v.step_nm];
            if let Some(other) = range.iter().find_map(|x| x.as_ref()) {
                self.invalid(
                    loc(list),
                    "wavelengths.list_nm",
                    format!(
                        "give either list_nm or start_nm/stop_nm/step_nm, not both (a range \
                         field is on line {})",
                        loc(other).0
                    ),
                );
            }
            let mut out = Vec::new();
            for x_at in &list.value {
                if let Some(x) = self.in_range("wavelengths.list_nm", x_at, lo, hi, false) {
                    if let Some(&p) = out.last().filter(|&&p| x <= p) {
                        self.out_of_range(
                            loc(x_at),
                            "wavelengths.list_nm",
                            x.to_string(),
                            format!("above the previous wavelength, ({p}, {hi}]"),
                        );
                    }
                    out.push(x);
                }
            }
            if out.is_empty() {
                self.invalid(loc(list), "wavelengths.list_nm", "empty list");
                return WavelengthGrid::thesis_default();
            }
            if out.len() as u64 > limits.wavelengths {
                self.over_limit(
                    loc(list),
                    "wavelengths.list_nm",
                    format!("{} wavelengths", count_text(out.len() as u64)),
                    "wavelengths",
                    count_text(limits.wavelengths),
                );
                return WavelengthGrid::thesis_default();
            }
            return WavelengthGrid::from_list(out);
        }
        let start = self.opt_range("wavelengths.start_nm", &v.start_nm, lo, hi, false, 400.0);
        let stop = self.opt_range("wavelengths.stop_nm", &v.stop_nm, lo, hi, false, 700.0);
        let step = self.opt_range("wavelengths.step_nm", &v.step_nm, 0.0, hi - lo, true, 10.0);
        if stop < start {
            match (&v.stop_nm, &v.start_nm) {
                (Some(s), _) => self.out_of_range(
                    loc(s),
                    "wavelengths.stop_nm",
                    stop.to_string(),
                    format!("[{start}, {hi}] (not below start_nm = {start})"),
                ),
                (None, Some(s)) => self.out_of_range(
                    loc(s),
                    "wavelengths.start_nm",
                    start.to_string(),
                    format!("[{lo}, {stop}] (not above the default stop_nm = {stop})"),
                ),
                (None, None) => {}
            }
            return WavelengthGrid::thesis_default();
        }
        // As WavelengthGrid::uniform counts them, in f64 so no step can overflow the count.
        let n = ((stop - start) / step + 1e-9).floor() + 1.0;
        if n > limits.wavelengths as f64 {
            let at = v.step_nm.as_ref().map_or_else(|| loc(w), loc);
            self.over_limit(
                at,
                "wavelengths.step_nm",
                format!(
                    "{}–{} nm in steps of {} nm gives {} wavelengths",
                    num(start),
                    num(stop),
                    num(step),
                    if n < 1e15 {
                        count_text(n as u64)
                    } else {
                        format!("{n:.3e}")
                    }
                ),
                "wavelengths",
                count_text(limits.wavelengths),
            );
            return WavelengthGrid::thesis_default();
        }
        WavelengthGrid::uniform(start, stop, step)
    }

    fn reject_lists(&mut self, p: &RawParams, block: &str) {
        let lists = [
            ("age", is_many(&p.age)),
            ("gender", is_many(&p.gender)),
            ("skin_type", is_many(&p.skin_type)),
            ("melanosome_fraction", is_many(&p.melanosome_fraction)),
            ("location", is_many(&p.location)),
            ("xi", is_many(&p.xi)),
            ("model", is_many(&p.model)),
        ];
        for (field, at) in lists {
            if let Some(at) = at {
                self.invalid(
                    at,
                    field,
                    format!("a list of values is only allowed in `sweeps`, not in `{block}`"),
                );
            }
        }
    }

    /// A swept value listed twice would bake the same entry twice under one name.
    fn reject_repeats(&mut self, p: &RawParams) {
        self.repeats("age", &p.age);
        self.repeats("gender", &p.gender);
        self.repeats("skin_type", &p.skin_type);
        self.repeats("melanosome_fraction", &p.melanosome_fraction);
        self.repeats("location", &p.location);
        self.repeats("xi", &p.xi);
        self.repeats("model", &p.model);
    }

    fn repeats<T: PartialEq + std::fmt::Display>(
        &mut self,
        field: &str,
        v: &Option<Spanned<OneOrMany<T>>>,
    ) {
        let Some(Spanned {
            value: OneOrMany::Many(list),
            ..
        }) = v
        else {
            return;
        };
        for (i, x) in list.iter().enumerate() {
            if let Some(first) = list[..i].iter().find(|y| y.value == x.value) {
                self.invalid(
                    loc(x),
                    field,
                    format!(
                        "{} is listed twice (first on line {}); allowed: each swept value once",
                        x.value,
                        loc(first).0
                    ),
                );
            }
        }
    }

    fn check_template(&mut self, template: &Spanned<String>, p: &RawParams) {
        let swept = [
            ("age", count(&p.age)),
            ("gender", count(&p.gender)),
            ("skin_type", count(&p.skin_type)),
            ("melanosome_fraction", count(&p.melanosome_fraction)),
            ("location", count(&p.location)),
            ("xi", count(&p.xi)),
            ("model", count(&p.model)),
        ];
        for (field, n) in swept {
            if n > 1 && !template.value.contains(&format!("{{{field}}}")) {
                self.invalid(
                    loc(template),
                    "name",
                    format!("the sweep varies {field}, so its name template needs {{{field}}} to keep entry names unique"),
                );
            }
        }
    }

    /// Builds the model inputs of one point; records errors and returns None if any.
    fn params(&mut self, p: &RawParams, pt: &Point, at: (u64, u64)) -> Option<SkinParams> {
        let before = self.errors.len();
        let age = match &pt.age {
            Some(a) => self.in_range("age", a, AGE_RANGE_YEARS.0, AGE_RANGE_YEARS.1, false),
            None => {
                self.invalid(at, "age", "missing (years, 18–90)");
                None
            }
        };
        let gender_opts = [("female", Gender::Female), ("male", Gender::Male)];
        let gender = match &pt.gender {
            Some(g) => self.choice("gender", g, &gender_opts),
            None => {
                self.invalid(at, "gender", "missing (female or male)");
                None
            }
        };
        let loc_opts = [
            ("face", BodyLocation::Face),
            ("forearm", BodyLocation::Forearm),
            ("back_of_hand", BodyLocation::BackOfHand),
            ("palm", BodyLocation::Palm),
        ];
        let location = match &pt.location {
            Some(l) => self.choice("location", l, &loc_opts),
            None => {
                self.invalid(
                    at,
                    "location",
                    "missing (face, forearm, back_of_hand or palm)",
                );
                None
            }
        };
        let xi = match &pt.xi {
            Some(x) => self.in_range("xi", x, 0.0, 1.0, false),
            None => {
                self.invalid(at, "xi", "missing (exposure to external aging agents, 0–1)");
                None
            }
        };
        let melanin = match (&pt.skin_type, &pt.melanosome_fraction) {
            (Some(t), None) => self.skin_type(t).map(MelaninInput::SkinType),
            (None, Some(f)) => self
                .in_range("melanosome_fraction", f, 0.0, 0.5, false)
                .map(MelaninInput::MelanosomeFraction),
            (Some(t), Some(f)) => {
                self.invalid(
                    loc(f),
                    "melanosome_fraction",
                    format!(
                        "give skin_type (line {}) or melanosome_fraction, not both",
                        loc(t).0
                    ),
                );
                None
            }
            (None, None) => {
                self.invalid(
                    at,
                    "skin_type",
                    "missing: give skin_type (I–VI) or melanosome_fraction (0–0.5)",
                );
                None
            }
        };
        let model = match &pt.model {
            Some(m) => self.choice(
                "model",
                m,
                &[
                    ("five_layer", ModelKind::FiveLayer),
                    ("three_layer", ModelKind::ThreeLayer),
                ],
            ),
            None => Some(ModelKind::FiveLayer),
        };
        let (Some(age), Some(gender), Some(location), Some(xi), Some(melanin), Some(model)) =
            (age, gender, location, xi, melanin, model)
        else {
            return None;
        };
        let mut s = SkinParams::new(age, gender, location, melanin, xi);
        s.model = model;
        self.overrides(p, &mut s);
        (self.errors.len() == before).then_some(s)
    }

    fn skin_type(&mut self, t: &Spanned<Token>) -> Option<SkinType> {
        let found = match &t.value {
            Token::Text(s) => SkinType::ALL
                .iter()
                .find(|k| k.roman() == s.as_str())
                .copied(),
            Token::Number(x) if x.fract() == 0.0 && (1.0..=6.0).contains(x) => {
                Some(SkinType::ALL[*x as usize - 1])
            }
            Token::Number(_) => None,
        };
        if found.is_none() {
            self.out_of_range(
                loc(t),
                "skin_type",
                t.value.to_string(),
                "one of I, II, III, IV, V, VI (or 1–6)".into(),
            );
        }
        found
    }

    /// Biophysical overrides; ranges cite the table that motivates them.
    fn overrides(&mut self, p: &RawParams, s: &mut SkinParams) {
        if let Some(v) = &p.skin_type_melanin {
            let opts = [
                ("caption", SkinTypeMelanin::Caption),
                ("figure40", SkinTypeMelanin::Figure40),
            ];
            if let Some(m) = self.choice("skin_type_melanin", v, &opts) {
                s.skin_type_melanin = m;
            }
        }
        // Table 2: ϑHb in [0.1, 20] % in the dermis.
        s.blood_fraction_pd = self.opt_range(
            "blood_fraction_pd",
            &p.blood_fraction_pd,
            0.001,
            0.2,
            false,
            s.blood_fraction_pd,
        );
        s.blood_fraction_rd = self.opt_range(
            "blood_fraction_rd",
            &p.blood_fraction_rd,
            0.001,
            0.2,
            false,
            s.blood_fraction_rd,
        );
        s.blood_fraction_hd = self.opt_range(
            "blood_fraction_hd",
            &p.blood_fraction_hd,
            0.0,
            0.2,
            false,
            s.blood_fraction_hd,
        );
        s.oxygen_saturation = self.opt_range(
            "oxygen_saturation",
            &p.oxygen_saturation,
            0.0,
            1.0,
            false,
            s.oxygen_saturation,
        );
        s.hemoglobin_g_per_l = self.opt_range(
            "hemoglobin_g_per_l",
            &p.hemoglobin_g_per_l,
            0.0,
            300.0,
            true,
            s.hemoglobin_g_per_l,
        );
        // Table 2: bilirubin [0.05, 3] g/L; 0 allowed to switch it off.
        s.bilirubin_g_per_l = self.opt_range(
            "bilirubin_g_per_l",
            &p.bilirubin_g_per_l,
            0.0,
            3.0,
            false,
            s.bilirubin_g_per_l,
        );
        s.carotene_blood_g_per_l = self.opt_range(
            "carotene_blood_g_per_l",
            &p.carotene_blood_g_per_l,
            0.0,
            0.01,
            false,
            s.carotene_blood_g_per_l,
        );
        s.carotene_epidermis_g_per_l = self.opt_range(
            "carotene_epidermis_g_per_l",
            &p.carotene_epidermis_g_per_l,
            0.0,
            0.01,
            false,
            s.carotene_epidermis_g_per_l,
        );
        s.eumelanin_g_per_l = self.opt_range(
            "eumelanin_g_per_l",
            &p.eumelanin_g_per_l,
            0.0,
            200.0,
            false,
            s.eumelanin_g_per_l,
        );
        s.pheomelanin_g_per_l = self.opt_range(
            "pheomelanin_g_per_l",
            &p.pheomelanin_g_per_l,
            0.0,
            200.0,
            false,
            s.pheomelanin_g_per_l,
        );
        if let Some(v) = &p.pheomelanin_absorption {
            let opts = [
                ("thesis_fit", PheomelaninAbsorption::ThesisFit),
                ("measured", PheomelaninAbsorption::Measured),
            ];
            if let Some(m) = self.choice("pheomelanin_absorption", v, &opts) {
                s.pheomelanin_absorption = m;
            }
        }
        if let Some(v) = &p.hypodermis_absorption {
            let opts = [
                ("blood", HypodermisAbsorption::Blood),
                ("water_only", HypodermisAbsorption::WaterOnly),
            ];
            if let Some(m) = self.choice("hypodermis_absorption", v, &opts) {
                s.hypodermis_absorption = m;
            }
        }
        self.layer_values(
            "water_fraction",
            &p.water_fraction,
            &mut s.water_fraction,
            (0.0, 0.95, false),
        );
        self.layer_values(
            "thickness_mm",
            &p.thickness_mm,
            &mut s.thickness_at_30_mm,
            (0.0, 100.0, true),
        );
        self.layer_values(
            "atrophy_per_decade",
            &p.atrophy_per_decade,
            &mut s.atrophy_per_decade,
            (0.0, 0.5, false),
        );
        s.dej_amplitude_at_30_um = self.opt_range(
            "dej_amplitude_um",
            &p.dej_amplitude_um,
            0.0,
            200.0,
            false,
            s.dej_amplitude_at_30_um,
        );
        s.dej_period_um = self.opt_range(
            "dej_period_um",
            &p.dej_period_um,
            10.0,
            2000.0,
            false,
            s.dej_period_um,
        );
        if let Some(ph) = &p.dej_phase_rad {
            if ph.value.iter().all(|x| x.is_finite()) {
                s.dej_phase_rad = ph.value;
            } else {
                self.out_of_range(
                    loc(ph),
                    "dej_phase_rad",
                    format!("{:?}", ph.value),
                    "two finite numbers".into(),
                );
            }
        }
        if let Some(v) = &p.rz_um {
            s.rz_um = self.in_range("rz_um", v, 0.0, 1000.0, true);
        }
        if let Some(v) = &p.sebum_mg {
            s.sebum_mg = self.in_range("sebum_mg", v, 0.0, 10.0, false);
        }
        s.sebum_volume_factor = self.opt_range(
            "sebum_volume_factor",
            &p.sebum_volume_factor,
            0.0,
            10.0,
            true,
            s.sebum_volume_factor,
        );
        if let Some(c) = &p.collagen_pd {
            s.collagen_pd = self.collagen("collagen_pd", &c.value);
        }
        if let Some(c) = &p.collagen_rd {
            s.collagen_rd = self.collagen("collagen_rd", &c.value);
        }
        if let Some(list) = &p.freeze {
            s.freeze = self.freeze(list);
        }
    }

    fn layer_values(
        &mut self,
        field: &str,
        raw: &Option<Spanned<RawLayerValues>>,
        out: &mut [f64; 5],
        range: (f64, f64, bool),
    ) {
        let Some(raw) = raw else { return };
        for (layer, v) in Layer::ALL.iter().zip(raw.value.as_array()) {
            if let Some(v) = v {
                let name = format!("{field}.{}", layer.key());
                if let Some(x) = self.in_range(&name, v, range.0, range.1, range.2) {
                    out[layer.index()] = x;
                }
            }
        }
    }

    fn collagen(&mut self, field: &str, c: &RawCollagen) -> CollagenAging {
        let mut one = |age: &str, s: &Spanned<super::raw::RawSkewNormal>| SkewNormal {
            location_um: self
                .in_range(
                    &format!("{field}.{age}.location_um"),
                    &s.value.location_um,
                    0.5,
                    40.0,
                    false,
                )
                .unwrap_or(1.0),
            scale_um: self
                .in_range(
                    &format!("{field}.{age}.scale_um"),
                    &s.value.scale_um,
                    0.05,
                    40.0,
                    false,
                )
                .unwrap_or(1.0),
            shape: self
                .in_range(
                    &format!("{field}.{age}.shape"),
                    &s.value.shape,
                    -20.0,
                    20.0,
                    false,
                )
                .unwrap_or(0.0),
        };
        CollagenAging {
            at_30: one("at_30", &c.at_30),
            at_80: one("at_80", &c.at_80),
        }
    }

    fn freeze(&mut self, list: &Spanned<Vec<Spanned<String>>>) -> Freeze {
        let mut f = Freeze::default();
        for item in &list.value {
            match item.value.as_str() {
                "thickness" => f.thickness = true,
                "melanin" => f.melanin = true,
                "hemoglobin" => f.hemoglobin = true,
                "surface" => f.surface = true,
                "collagen" => f.collagen = true,
                "junction" => f.junction = true,
                other => self.out_of_range(
                    loc(item),
                    "freeze",
                    format!("{other:?}"),
                    "thickness, melanin, hemoglobin, surface, collagen, junction".into(),
                ),
            }
        }
        f
    }
}

fn is_many<T>(v: &Option<Spanned<OneOrMany<T>>>) -> Option<(u64, u64)> {
    match v {
        Some(s) if matches!(s.value, OneOrMany::Many(_)) => Some(loc(s)),
        _ => None,
    }
}

fn count<T>(v: &Option<Spanned<OneOrMany<T>>>) -> usize {
    match v {
        Some(Spanned {
            value: OneOrMany::Many(m),
            ..
        }) => m.len(),
        _ => 1,
    }
}

/// The values of a sweepable field, each with its own location.
fn values<T: Clone>(v: &Option<Spanned<OneOrMany<T>>>) -> Vec<Option<Spanned<T>>> {
    match v {
        None => vec![None],
        Some(s) => match &s.value {
            OneOrMany::One(x) => vec![Some(Spanned::new(x.clone(), s.referenced, s.defined))],
            OneOrMany::Many(list) if list.is_empty() => vec![None],
            OneOrMany::Many(list) => list.iter().cloned().map(Some).collect(),
        },
    }
}

fn single_point(p: &RawParams) -> Point {
    expand(p).into_iter().next().unwrap_or_default()
}

/// The message for a name equal to an earlier one (`first`, on `first_line`), or equal but for
/// case (one file on macOS and Windows file systems).
pub(super) fn duplicate_message(name: &str, first: &str, first_line: u64) -> String {
    if first == name {
        format!("{name:?} already defined on line {first_line}")
    } else {
        format!(
            "{name:?} differs from {first:?} (line {first_line}) only in case; allowed: names \
             that differ in more than case (they name files, and macOS and Windows file \
             systems ignore case)"
        )
    }
}

/// How many points [`expand`] gives, without building them (saturating).
fn point_count(p: &RawParams) -> u64 {
    [
        count(&p.age),
        count(&p.gender),
        count(&p.skin_type),
        count(&p.melanosome_fraction),
        count(&p.location),
        count(&p.xi),
        count(&p.model),
    ]
    .iter()
    .fold(1u64, |a, &n| a.saturating_mul(n.max(1) as u64))
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

/// Cartesian product of the sweepable fields, in the order they are declared.
fn expand(p: &RawParams) -> Vec<Point> {
    let mut points = vec![Point::default()];
    macro_rules! product {
        ($field:ident) => {{
            let vals = values(&p.$field);
            let mut next = Vec::with_capacity(points.len() * vals.len());
            for pt in &points {
                for v in &vals {
                    let mut q = pt.clone();
                    q.$field = v.clone();
                    next.push(q);
                }
            }
            points = next;
        }};
    }
    product!(age);
    product!(gender);
    product!(skin_type);
    product!(melanosome_fraction);
    product!(location);
    product!(xi);
    product!(model);
    points
}

fn fill_template(template: &str, pt: &Point) -> String {
    let mut name = template.to_string();
    let mut put = |key: &str, v: Option<String>| {
        if let Some(v) = v {
            name = name.replace(&format!("{{{key}}}"), &v);
        }
    };
    put("age", pt.age.as_ref().map(|v| v.value.to_string()));
    put("gender", pt.gender.as_ref().map(|v| v.value.clone()));
    put(
        "skin_type",
        pt.skin_type.as_ref().map(|v| v.value.to_string()),
    );
    put(
        "melanosome_fraction",
        pt.melanosome_fraction.as_ref().map(|v| v.value.to_string()),
    );
    put("location", pt.location.as_ref().map(|v| v.value.clone()));
    put("xi", pt.xi.as_ref().map(|v| v.value.to_string()));
    put("model", pt.model.as_ref().map(|v| v.value.clone()));
    name
}

/// `over` on top of `base`, field by field (per-layer maps merge per layer).
fn merge(base: &RawParams, over: &RawParams) -> RawParams {
    macro_rules! pick {
        ($($f:ident),*) => {
            RawParams { $($f: over.$f.clone().or_else(|| base.$f.clone()),)* ..merge_layers(base, over) }
        };
    }
    pick!(
        name,
        age,
        gender,
        skin_type,
        melanosome_fraction,
        location,
        xi,
        model,
        skin_type_melanin,
        blood_fraction_pd,
        blood_fraction_rd,
        blood_fraction_hd,
        oxygen_saturation,
        hemoglobin_g_per_l,
        bilirubin_g_per_l,
        carotene_blood_g_per_l,
        carotene_epidermis_g_per_l,
        eumelanin_g_per_l,
        pheomelanin_g_per_l,
        pheomelanin_absorption,
        hypodermis_absorption,
        dej_amplitude_um,
        dej_period_um,
        dej_phase_rad,
        rz_um,
        sebum_mg,
        sebum_volume_factor,
        collagen_pd,
        collagen_rd,
        freeze
    )
}

fn merge_layers(base: &RawParams, over: &RawParams) -> RawParams {
    let m = |b: &Option<Spanned<RawLayerValues>>, o: &Option<Spanned<RawLayerValues>>| match (b, o)
    {
        (Some(b), Some(o)) => {
            let (bv, ov) = (&b.value, &o.value);
            let v = RawLayerValues {
                stratum_corneum: ov
                    .stratum_corneum
                    .clone()
                    .or_else(|| bv.stratum_corneum.clone()),
                living_epidermis: ov
                    .living_epidermis
                    .clone()
                    .or_else(|| bv.living_epidermis.clone()),
                papillary_dermis: ov
                    .papillary_dermis
                    .clone()
                    .or_else(|| bv.papillary_dermis.clone()),
                reticular_dermis: ov
                    .reticular_dermis
                    .clone()
                    .or_else(|| bv.reticular_dermis.clone()),
                hypodermis: ov.hypodermis.clone().or_else(|| bv.hypodermis.clone()),
            };
            Some(Spanned::new(v, o.referenced, o.defined))
        }
        (b, o) => o.clone().or_else(|| b.clone()),
    };
    RawParams {
        water_fraction: m(&base.water_fraction, &over.water_fraction),
        thickness_mm: m(&base.thickness_mm, &over.thickness_mm),
        atrophy_per_decade: m(&base.atrophy_per_decade, &over.atrophy_per_decade),
        ..RawParams::default()
    }
}
