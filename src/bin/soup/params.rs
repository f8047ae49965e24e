//! The pipeline options of `soup reconstruct` and `soup eval`.
//!
//! Every default shown by `--help` is read from the library (`Params::default()`,
//! `Preset::default()`), and every parameter without an option keeps its library default, so
//! the CLI, the page (which reads the same defaults through `pageDefaults`) and the library
//! cannot drift apart.

use std::path::{Path, PathBuf};
use superpixel_soup::flow::{FlowParams, Preset};

use superpixel_soup::{Error, Params, Result};

/// Options that set pipeline parameters; the rest keep `Params::default()`.
#[derive(clap::Args)]
pub struct PipelineArgs {
    /// Preset of the computed flow: fast, medium, fine or high (finer pyramid levels, denser
    /// patches and more iterations are slower and usually more accurate).
    #[arg(long, default_value_t = Preset::default().name().to_string())]
    pub preset: String,
    /// Requested number of SLIC superpixels (the pieces of the soup; the result is within a few
    /// percent of it).
    #[arg(long, default_value_t = Params::default().superpixels.count)]
    pub superpixels: usize,
    /// SLIC compactness m: weight of spatial against colour distance; larger gives more regular,
    /// less colour-driven superpixels.
    #[arg(long, default_value_t = Params::default().superpixels.compactness)]
    pub compactness: f32,
    /// Neighbours per superpixel in the K-NN graph (local motion hypotheses are fitted on a
    /// superpixel together with these).
    #[arg(long, default_value_t = Params::default().k)]
    pub k: usize,
    /// Reconstructions fused into the result, from superpixel counts around `--superpixels`:
    /// each superpixel's scale is their median (1 turns fusion off; each more costs about a
    /// third of one reconstruction).
    #[arg(long, default_value_t = Params::default().ensemble.members)]
    pub members: usize,
    /// A JSON file setting any pipeline parameters (the shape of `params` in report.json; fields
    /// left out keep their defaults, nested objects are merged). An option above overrides the
    /// file when it differs from its default.
    #[arg(long)]
    pub params: Option<PathBuf>,
}

impl PipelineArgs {
    /// `Params::default()` with the `--params` file and the options given on the command line.
    ///
    /// Errors: the file cannot be read, is not JSON, or holds a field of the wrong type.
    pub fn params(&self) -> Result<Params> {
        let defaults = match &self.params {
            Some(path) => params_from_file(path)?,
            None => Params::default(),
        };
        let library = Params::default();
        let mut params = defaults;
        // An option at its library default leaves the file's value alone.
        if self.superpixels != library.superpixels.count {
            params.superpixels.count = self.superpixels;
        }
        if self.compactness != library.superpixels.compactness {
            params.superpixels.compactness = self.compactness;
        }
        if self.k != library.k {
            params.k = self.k;
        }
        if self.members != library.ensemble.members {
            params.ensemble.members = self.members;
        }
        Ok(params)
    }

    /// The flow parameters of `--preset`.
    pub fn flow_params(&self) -> Result<FlowParams> {
        Ok(FlowParams::preset(Preset::from_name(&self.preset)?))
    }
}

/// `Params::default()` with the fields of the JSON file at `path` merged in.
fn params_from_file(path: &Path) -> Result<Params> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let bad = |e: serde_json::Error| {
        Error::InvalidParameter(format!("{}: not valid parameters: {e}", path.display()))
    };
    let given: serde_json::Value = serde_json::from_str(&text).map_err(bad)?;
    let mut merged = serde_json::to_value(Params::default()).map_err(bad)?;
    merge(&mut merged, given, "").map_err(|field| {
        Error::InvalidParameter(format!("{}: unknown parameter {field}", path.display()))
    })?;
    serde_json::from_value(merged).map_err(bad)
}

/// Merges `given` into `base`: objects field by field, anything else replaced. Errors with the
/// dotted name of a field that `base` does not have (a typo would otherwise pass unnoticed).
fn merge(
    base: &mut serde_json::Value,
    given: serde_json::Value,
    at: &str,
) -> std::result::Result<(), String> {
    match (base, given) {
        (serde_json::Value::Object(b), serde_json::Value::Object(g)) => {
            for (key, value) in g {
                let name = format!("{at}{key}");
                let slot = b.get_mut(&key).ok_or_else(|| name.clone())?;
                merge(slot, value, &format!("{name}."))?;
            }
            Ok(())
        }
        (slot, value) => {
            *slot = value;
            Ok(())
        }
    }
}

/// Text after `--help`: every pipeline parameter with its default, as the JSON that
/// `report.json` records, including those without an option.
pub fn all_defaults_help() -> String {
    let json = serde_json::to_string_pretty(&Params::default())
        .unwrap_or_else(|e| format!("(cannot list the defaults: {e})"));
    format!(
        "Every pipeline parameter and its default (the options above set some; the meaning of \
         each is documented on `Params` and the types it holds, `cargo doc --open`):\n{json}"
    )
}
