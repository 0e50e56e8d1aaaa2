//! The skin-optics document ([`formats::optics`]) built from model results: what `optics.json`
//! and every later stage (transport stacks, tables, exports) read.

use formats::optics::{self, OpticsDocument, OpticsEntry, OpticsLayer};

use super::{ModelKind, SkinOptics, SkinParams};

pub fn model_name(m: ModelKind) -> &'static str {
    match m {
        ModelKind::FiveLayer => "five_layer",
        ModelKind::ThreeLayer => "three_layer",
    }
}

/// The document entry of `name`, evaluated from `params` as `o`.
pub fn entry(name: &str, params: &SkinParams, o: &SkinOptics) -> OpticsEntry {
    let j = o.junction;
    let s = o.surface;
    OpticsEntry {
        name: name.to_string(),
        model: model_name(o.model).to_string(),
        inputs: serde_json::to_value(params).expect("parameters serialise"),
        layers: o
            .layers
            .iter()
            .map(|l| OpticsLayer {
                name: l.name.to_string(),
                d_mm: l.d_mm,
                eta: l.eta,
                mua_per_mm: l.mua_per_mm.clone(),
                musp_per_mm: l.musp_per_mm.clone(),
            })
            .collect(),
        junction: j,
        surface: s,
        intermediate: serde_json::to_value(&o.intermediate).expect("intermediate serialises"),
    }
}

pub fn document(source: &str, lambda_nm: &[f64], entries: Vec<OpticsEntry>) -> OpticsDocument {
    OpticsDocument {
        format: optics::FORMAT.to_string(),
        version: optics::VERSION,
        source: source.to_string(),
        lambda_nm: lambda_nm.to_vec(),
        entries,
    }
}
