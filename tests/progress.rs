//! The preprocess phase reporting (`forecast::progress::Phases`): a recording sink sees the
//! phases of `iws-cf` (budget pilot, tracing with stored/requested counts, clustering, maps) and
//! of `iws-pm` in order, and reporting leaves the preprocess product unchanged (the render bar's
//! visibility rules are the pipeline's; indicatif hides both when stderr is not a terminal).

use forecast::accel::World;
use forecast::cf::estimator::CausticForecast;
use forecast::integrators::iws_cf::LEAST_BUDGET_PHOTONS;
use forecast::integrators::iws_pm::PhotonMap;
use forecast::integrators::{Method, MethodArgs};
use forecast::progress::Phases;
use std::path::Path;
use std::sync::Mutex;

/// One reported event.
#[derive(Debug, PartialEq)]
enum Event {
    Begin(&'static str, Option<u64>),
    Advance(u64),
    End,
}

/// The test sink: records every event in order.
#[derive(Default)]
struct Recorder(Mutex<Vec<Event>>);

impl Phases for Recorder {
    fn begin(&self, name: &'static str, total: Option<u64>) {
        self.0.lock().unwrap().push(Event::Begin(name, total));
    }
    fn advance(&self, done: u64) {
        self.0.lock().unwrap().push(Event::Advance(done));
    }
    fn end(&self) {
        self.0.lock().unwrap().push(Event::End);
    }
}

/// The phases as (name, total, counts advanced to); panics unless each phase is one
/// begin, its advances and one end, with nothing outside a phase.
fn phases(events: Vec<Event>) -> Vec<(&'static str, Option<u64>, Vec<u64>)> {
    let mut out: Vec<(&'static str, Option<u64>, Vec<u64>)> = Vec::new();
    let mut open = false;
    for e in events {
        match e {
            Event::Begin(name, total) => {
                assert!(!open, "{name} began inside another phase");
                out.push((name, total, Vec::new()));
                open = true;
            }
            Event::Advance(n) => {
                assert!(open, "advance outside a phase");
                out.last_mut().unwrap().2.push(n);
            }
            Event::End => {
                assert!(open, "end outside a phase");
                open = false;
            }
        }
    }
    assert!(!open, "the last phase never ended");
    out
}

fn ring() -> World {
    World::build(forecast::scene::load(Path::new("scenes/ring.toml")).expect("scene loads")).expect("BVH builds")
}

/// The product without its timings (wall-clock figures differ between any two runs).
fn untimed(bytes: &[u8]) -> CausticForecast {
    let mut cf = CausticForecast::from_bytes(bytes).unwrap();
    (cf.stats.tracing_s, cf.stats.clustering_s, cf.stats.kdtree_s, cf.stats.pilot_s_per_photon) = (0.0, 0.0, 0.0, 0.0);
    cf.stats.shares_s = 0.0;
    cf
}

#[test]
fn iws_cf_reports_pilot_tracing_clustering_maps_in_order() {
    let w = ring();
    let mut o = MethodArgs::default();
    // no explicit count and a 10-ms budget: the pilot runs and the rule picks its least count (the
    // floor of MIN_BUDGET_PHOTONS yields to a budget it would overrun, issue #63)
    (o.cf.forecast_photons, o.cf.time_budget_s, o.cf.clusters) = (None, Some(0.01), 16);
    let rec = Recorder::default();
    let bytes = Method::IwsCf.preprocess_reporting(&w, &o, 17, &rec).unwrap();
    let got = phases(rec.0.into_inner().unwrap());
    let names: Vec<_> = got.iter().map(|p| p.0).collect();
    assert_eq!(names, ["pilot", "tracing forecast photons", "clustering", "building forecast maps", "caustic shares"]);
    let (_, total, counts) = &got[1];
    assert_eq!(*total, Some(LEAST_BUDGET_PHOTONS));
    assert!(!counts.is_empty() && counts.windows(2).all(|c| c[0] <= c[1]), "{counts:?}");
    let cf = untimed(&bytes);
    assert_eq!(cf.stats.photons_requested, LEAST_BUDGET_PHOTONS);
    assert_eq!(*counts.last().unwrap(), cf.stats.stored, "the last count is the photons stored");
    assert!(got[0].2.is_empty() && got[2].2.is_empty() && got[3].2.is_empty() && got[4].2.is_empty());
    // reporting never changes the product
    assert_eq!(cf, untimed(&Method::IwsCf.preprocess(&w, &o, 17).unwrap()));
}

#[test]
fn iws_pm_reports_its_photon_map_and_pt_reports_nothing() {
    let w = ring();
    let mut o = MethodArgs::default();
    o.pm.photons = 5_000;
    let rec = Recorder::default();
    let bytes = Method::IwsPm.preprocess_reporting(&w, &o, 3, &rec).unwrap();
    let got = phases(rec.0.into_inner().unwrap());
    assert_eq!(got.len(), 1);
    let (name, total, counts) = &got[0];
    assert_eq!((*name, *total), ("photon map", Some(5_000)));
    assert!(!counts.is_empty() && counts.windows(2).all(|c| c[0] <= c[1]), "{counts:?}");
    // cosine emission rarely reaches the ring: the collector may stop at its path cap first
    let pm: PhotonMap = bitcode::decode(&bytes).unwrap();
    assert_eq!(*counts.last().unwrap(), pm.len() as u64, "the last count is the photons stored");
    let rec = Recorder::default();
    Method::Pt.preprocess_reporting(&w, &o, 3, &rec).unwrap();
    assert!(rec.0.into_inner().unwrap().is_empty());
}

/// The time-mode bar reads the time box's own clock: 5 s into a 120 s box, 1:55 is left (the
/// rate estimate it replaces read 18 s there, issue #63); an hour shows as H:MM:SS; a spent box
/// reads 0 left, never negative.
#[test]
fn time_box_bar_counts_down_the_budget() {
    use forecast::progress::time_box_clock;
    assert_eq!(time_box_clock(5.0, 120.0), "00:05 / 01:55 left");
    assert_eq!(time_box_clock(0.0, 3600.0 + 61.0), "00:00 / 1:01:01 left");
    assert_eq!(time_box_clock(121.4, 120.0), "02:01 / 00:00 left");
}
