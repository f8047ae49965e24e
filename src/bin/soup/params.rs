//! The pipeline options of `soup reconstruct` and `soup eval`.
//!
//! Every default shown by `--help` is read from the library (`Params::default()`,
//! `Preset::default()`), and every parameter without an option keeps its library default, so
//! the CLI, the page (which reads the same defaults through `pageDefaults`) and the library
//! cannot drift apart.

use superpixel_soup::flow::{FlowParams, Preset};
use superpixel_soup::superpixels::SlicParams;
use superpixel_soup::{Params, Result};

/// Options that set pipeline parameters; the rest keep `Params::default()`.
#[derive(clap::Args)]
pub struct PipelineArgs {
    /// Preset of the computed flow: fast, medium or high (finer pyramid levels, denser patches
    /// and more iterations are slower and usually more accurate).
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
    /// β of the neighbour weights exp(−β ‖s_i − s_k‖), anchors s in units of the image's long
    /// side: larger ties each superpixel to its nearest neighbours only.
    #[arg(long, default_value_t = Params::default().beta)]
    pub beta: f64,
}

impl PipelineArgs {
    /// `Params::default()` with the options given on the command line.
    pub fn params(&self) -> Params {
        let defaults = Params::default();
        Params {
            superpixels: SlicParams {
                count: self.superpixels,
                compactness: self.compactness,
                ..defaults.superpixels
            },
            k: self.k,
            beta: self.beta,
            ..defaults
        }
    }

    /// The flow parameters of `--preset`.
    pub fn flow_params(&self) -> Result<FlowParams> {
        Ok(FlowParams::preset(Preset::from_name(&self.preset)?))
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
