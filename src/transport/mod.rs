//! Light-transport pieces shared by the integrators: next-event estimation with MIS
//! (`direct`), the one particle tracer behind VPLs, caustic photons and forecasters
//! (`particle`, with the one caustic-point collector and the emission samplers), Dirac-chain
//! following (`dirac`), the one Russian-roulette rule (`roulette`), RIS point-light selection
//! (`light_select`), the targeted emission's cones (`target`) and the per-worker context handed
//! down the recursion (`context`).

pub mod context;
pub mod dirac;
pub mod direct;
pub mod light_select;
pub mod particle;
pub mod roulette;
pub mod target;
