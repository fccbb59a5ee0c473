//! Light-transport helpers shared by the integrators: next-event estimation with MIS
//! (`direct`) and the one particle tracer behind VPLs, caustic photons and forecasters
//! (`particle`).

pub mod direct;
pub mod light_select;
pub mod particle;
