//! Timings of the soup stages (everything after flow and superpixels: the focal length's search
//! where none was given, motion hypotheses,
//! assignment, planes, contact scales, refinement, fusion of the members, outputs) at 1024×436
//! with exact flow, one thread except the fusion's members, which natively run on up to four
//! threads (as many as there are cores). Run with `cargo bench --bench soup`.

mod common;

use superpixel_soup::camera::Intrinsics;
use superpixel_soup::flow::is_known;
use superpixel_soup::focal::estimate_focal;
use superpixel_soup::input::prepare_pair;
use superpixel_soup::output::{dense_depth, point_clouds};
use superpixel_soup::soup::init::{InitParams, unit_scale_soup};
use superpixel_soup::soup::refine::{Problem, RefineParams, refine};
use superpixel_soup::soup::scales::{ScaleInputs, ScaleParams, solve_scales};
use superpixel_soup::superpixels::graph::{boundary_graph, knn_graph};
use superpixel_soup::superpixels::{SlicParams, slic};
use superpixel_soup::synth::{SceneKind, render};
use superpixel_soup::{FlowInput, Params, Stage, reconstruct};

fn main() {
    common::print_header(
        "Soup stages after flow and superpixels, native release, one core (fusion: up to four)",
    );
    for kind in SceneKind::ALL {
        let Ok(s) = render(kind, 1024, 436) else {
            return;
        };
        let Ok(sp) = slic(&s.frame1, &SlicParams::default()) else {
            return;
        };
        let boundaries = boundary_graph(&sp, &s.frame1);
        let adjacency = boundaries.adjacency(sp.len());
        let knn = knn_graph(&sp, 15, 3.0);
        let reliable = s.flow12.map(|&f| is_known(f));
        let k = s.intrinsics;
        let params = InitParams::default();
        let scales = ScaleParams::default();
        let inputs = ScaleInputs {
            superpixels: &sp,
            boundaries: &boundaries,
            flow: &s.flow12,
            reliable: &reliable,
            intrinsics: &k,
        };
        // The focal length's search, which runs only where no focal length was given.
        let guess = Intrinsics::default_for(1024, 436);
        let times = common::time_ms(3, || estimate_focal(&s.flow12, &reliable, &guess));
        common::print_row(
            &format!("focal length from the flow ({})", kind.name()),
            "1024×436",
            &times,
        );
        let init = || unit_scale_soup(&sp, &knn, &adjacency, &s.flow12, &reliable, &k, &params);
        let times = common::time_ms(3, init);
        common::print_row(
            &format!("unit-scale soup ({})", kind.name()),
            "1024×436",
            &times,
        );
        let Ok(unit) = init() else { return };
        let times = common::time_ms(3, || {
            let mut soup = unit.clone();
            solve_scales(&mut soup, &inputs, &scales)
        });
        common::print_row(&format!("scales ({})", kind.name()), "1024×436", &times);
        let mut soup = unit.clone();
        solve_scales(&mut soup, &inputs, &scales);
        // The default refinement is timed 3 times (its single runs varied by 30 % on a shared
        // machine); the paper preset, at 15-20 s, once.
        for (name, refine_params, runs) in [
            ("refinement", RefineParams::default(), 3),
            ("refinement, paper preset", RefineParams::paper(), 1),
        ] {
            let times = common::time_ms(runs, || {
                let mut refined = soup.clone();
                let problem = Problem::new(&refined, &inputs, &scales, &refine_params);
                refine(&mut refined, &problem, &inputs, &scales)
            });
            common::print_row(&format!("{name} ({})", kind.name()), "1024×436", &times);
        }
        let times = common::time_ms(3, || {
            let depth = dense_depth(&soup, &sp.labels, &k);
            point_clouds(&soup, &sp.labels, &depth, &s.frame1, &k)
        });
        common::print_row(
            &format!("depth + clouds ({})", kind.name()),
            "1024×436",
            &times,
        );
        // The fusion's members (superpixels, unit-scale soup, scales and the members'
        // refinement at four other counts, then the fusion) as the pipeline times them.
        let Ok(pair) = prepare_pair(
            s.frame1.clone().into(),
            s.frame2.clone().into(),
            Some(k),
            1024,
        ) else {
            return;
        };
        let fusion: Vec<f64> = (0..3)
            .filter_map(|_| {
                let flow = FlowInput::Given(s.flow12.clone());
                let rec = reconstruct(&pair, flow, &Params::default(), &mut |_, _| {}).ok()?;
                let timings = rec.report.timings_ms;
                timings
                    .iter()
                    .find(|(st, _)| *st == Stage::Ensemble)
                    .map(|t| t.1)
            })
            .collect();
        common::print_row(
            &format!("fusion, 4 members ({})", kind.name()),
            "1024×436",
            &fusion,
        );
    }
}
