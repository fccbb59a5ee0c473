//! Single-process [`Cluster`]: rank 0 of a world of size 1.
//!
//! Every collective is the identity on this one rank: a broadcast leaves the buffer
//! unchanged, a reduction returns a copy of the input, a gather returns the one blob.
//! It needs no MPI libraries and is what `init()` returns without the `mpi` feature.

use super::Cluster;

/// The one-process cluster (rank 0, size 1).
#[derive(Debug, Default, Clone, Copy)]
pub struct Local;

impl Local {
    /// Creates the single-process cluster.
    pub fn new() -> Self {
        Local
    }
}

impl Cluster for Local {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn broadcast_bytes(&self, _bytes: &mut Vec<u8>) {}
    fn reduce_sum(&self, local: &[f64]) -> Option<Vec<f64>> {
        Some(local.to_vec())
    }
    fn all_reduce_sum(&self, local: &[f64]) -> Vec<f64> {
        local.to_vec()
    }
    fn all_reduce_max(&self, local: f64) -> f64 {
        local
    }
    fn gather_bytes(&self, local: &[u8]) -> Option<Vec<Vec<u8>>> {
        Some(vec![local.to_vec()])
    }
    fn barrier(&self) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn topology() {
        let c = Local::new();
        assert_eq!((c.rank(), c.size()), (0, 1));
    }

    #[test]
    fn collectives_are_identity() {
        let c = Local::new();
        let mut b = vec![1u8, 2, 3];
        c.broadcast_bytes(&mut b);
        assert_eq!(b, [1, 2, 3]);
        assert_eq!(c.reduce_sum(&[1.0, -2.5]), Some(vec![1.0, -2.5]));
        assert_eq!(c.reduce_sum(&[]), Some(vec![]));
        assert_eq!(c.all_reduce_sum(&[4.0]), vec![4.0]);
        assert_eq!(c.all_reduce_max(-7.0), -7.0);
        assert_eq!(c.gather_bytes(b"hi"), Some(vec![b"hi".to_vec()]));
        assert_eq!(c.gather_bytes(b""), Some(vec![Vec::new()]));
        c.barrier();
    }

    #[test]
    fn usable_as_trait_object() {
        let c: Box<dyn Cluster> = Box::new(Local::new());
        assert_eq!(c.size(), 1);
        assert_eq!(c.reduce_sum(&[3.0]).map(|v| v[0]), Some(3.0));
    }
}
