//! Embree as the rival of `bench bvh`, and the round-robin timing that compares them fairly on a
//! shared machine.

use super::TIMED_PASSES;
use crate::error::Result;
use halfray_core::Ray;
use std::time::Instant;

/// A hit-or-miss query on a ray.
type HitQuery<'a> = Box<dyn Fn(&Ray) -> bool + 'a>;

/// Best-of-[`TIMED_PASSES`] throughputs (Mrays/s) of each of `fs` over `rays`, the passes taken
/// round-robin (pass 1 of every function, then pass 2, …).
pub(in crate::bench) fn interleaved(rays: &[Ray], fs: &[&dyn Fn(&Ray) -> bool]) -> Vec<f64> {
    let mut best = vec![f64::INFINITY; fs.len()];
    for _ in 0..TIMED_PASSES {
        for (f, b) in fs.iter().zip(best.iter_mut()) {
            let t0 = Instant::now();
            let hits = rays.iter().filter(|r| f(std::hint::black_box(r))).count();
            std::hint::black_box(hits);
            *b = b.min(t0.elapsed().as_secs_f64());
        }
    }
    best.iter()
        .map(|s| rays.len() as f64 / s.max(1e-9) / 1e6)
        .collect()
}

/// Embree in its default and robust modes over the same mesh, built pass by pass beside
/// halfray's tree.
#[cfg(feature = "embree")]
pub(super) struct Rivals {
    device: crate::embree::EmbreeDevice,
    positions: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    /// `[default, robust]`, from the last pass.
    scenes: Vec<crate::embree::EmbreeScene>,
    build_ms: [f64; 2],
}

#[cfg(feature = "embree")]
impl Rivals {
    pub(super) fn new(obj: &crate::obj::ObjMesh) -> Result<Option<Self>> {
        Ok(Some(Self {
            device: crate::embree::EmbreeDevice::new()?,
            positions: obj.positions.iter().map(|p| p.to_array()).collect(),
            triangles: obj.triangles.clone(),
            scenes: Vec::new(),
            build_ms: [f64::INFINITY; 2],
        }))
    }

    /// Builds both scenes once, keeping the best times and the new scenes.
    pub(super) fn build_pass(&mut self) -> Result<()> {
        self.scenes.clear();
        for (k, robust) in [false, true].into_iter().enumerate() {
            let t0 = Instant::now();
            let s = crate::embree::EmbreeScene::new(
                &self.device,
                &self.positions,
                &self.triangles,
                robust,
            )?;
            self.build_ms[k] = self.build_ms[k].min(t0.elapsed().as_secs_f64() * 1e3);
            self.scenes.push(s);
        }
        Ok(())
    }

    pub(super) fn build_ms(&self) -> [f64; 2] {
        self.build_ms
    }

    /// Closest-hit queries of the two scenes (hit or miss), `[default, robust]`.
    pub(super) fn closest(&self) -> Vec<HitQuery<'_>> {
        self.scenes
            .iter()
            .map(|s| {
                Box::new(move |r: &Ray| s.intersect_ray(r).is_some()) as Box<dyn Fn(&Ray) -> bool>
            })
            .collect()
    }
}

/// Without the `embree` feature there is no rival.
#[cfg(not(feature = "embree"))]
pub(super) struct Rivals;

#[cfg(not(feature = "embree"))]
impl Rivals {
    pub(super) fn new(_obj: &crate::obj::ObjMesh) -> Result<Option<Self>> {
        Ok(None)
    }
    pub(super) fn build_pass(&mut self) -> Result<()> {
        Ok(())
    }
    pub(super) fn build_ms(&self) -> [f64; 2] {
        [f64::NAN; 2]
    }
    pub(super) fn closest(&self) -> Vec<HitQuery<'_>> {
        Vec::new()
    }
}
