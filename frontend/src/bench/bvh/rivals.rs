//! Embree as the rival of `bench bvh`: its default and robust scenes over the same mesh, built
//! pass by pass beside halfray's tree and queried with `rtcIntersect1` (closest hit) or
//! `rtcOccluded1` (any hit) on the same rays, and with `rtcIntersect8`/`16` or
//! `rtcOccluded8`/`16` (the packet API) beside halfray's batch path.

use crate::error::Result;
use crate::raysets::named::Query;
use halfray_core::Ray;

/// A hit-or-miss query on a ray.
pub(super) type HitQuery<'a> = Box<dyn Fn(&Ray) -> bool + 'a>;

/// A closest-hit query on a whole set of rays, answering the number of hits.
pub(super) type BatchQuery<'a> = crate::timing::OwnedBatchSide<'a>;

/// Embree in its default and robust modes over the same mesh.
#[cfg(feature = "embree")]
pub(super) struct Rivals {
    device: crate::embree::EmbreeDevice,
    /// A device on every hardware thread (Embree's own default), for the all-threads build:
    /// alive from the first all-threads pass, which follows every one-thread build, until the
    /// mesh's rivals are dropped. Embree runs every device's builds on as many threads as the
    /// live device that asks for the most (`Device::getMaxNumThreads`, one task scheduler per
    /// process): alive during the one-thread builds, it made them use every hardware thread
    /// (seen in `perf`). Not dropped before the timed queries: Embree then caps its TBB
    /// scheduler at `device`'s one thread (`tbb::global_control`), and the workers the
    /// all-threads build started spin in `sched_yield` while the cap lasts (oneTBB issue
    /// #1417): a second busy thread through every timed query of both sides (`perf stat`:
    /// 1.99 CPUs used by a one-mesh `bench bvh`, 0.97 with the device kept). Dropped with the
    /// mesh's rivals, it leaves that spin to the next mesh's one-thread builds (both sides'
    /// alike, timed in turns), until the next all-threads pass lifts the cap.
    device_threads: Option<crate::embree::EmbreeDevice>,
    /// The mesh checked and laid out for Embree before any timed build, so that a timed
    /// build is Embree's own work (scene, geometry over these shared buffers, commit).
    mesh: crate::embree::EmbreeMesh,
    /// `[default, robust]`, from the last pass.
    scenes: Vec<crate::embree::EmbreeScene>,
    /// `[default, robust, default on all threads]`.
    build_ms: [f64; 3],
}

#[cfg(feature = "embree")]
impl Rivals {
    /// Embree's side for `obj`: the one-thread device, and the mesh checked and laid out for
    /// Embree (untimed). Fails on an index out of range.
    pub(super) fn new(obj: &crate::obj::ObjMesh) -> Result<Option<Self>> {
        Ok(Some(Self {
            device: crate::embree::EmbreeDevice::new()?,
            device_threads: None,
            mesh: crate::embree::EmbreeMesh::new(
                &obj.positions
                    .iter()
                    .map(|p| p.to_array())
                    .collect::<Vec<_>>(),
                &obj.triangles,
            )?,
            scenes: Vec::new(),
            build_ms: [f64::INFINITY; 3],
        }))
    }

    /// Builds both scenes once, keeping the best times and the new scenes. A time is of
    /// [`EmbreeScene::from_mesh`](crate::embree::EmbreeScene::from_mesh) alone: the mesh was
    /// checked and laid out in [`Rivals::new`].
    pub(super) fn build_pass(&mut self) -> Result<()> {
        self.scenes.clear();
        for (k, robust) in [false, true].into_iter().enumerate() {
            let t0 = std::time::Instant::now();
            let s = crate::embree::EmbreeScene::from_mesh(&self.device, &self.mesh, robust)?;
            self.build_ms[k] = self.build_ms[k].min(t0.elapsed().as_secs_f64() * 1e3);
            self.scenes.push(s);
        }
        Ok(())
    }

    /// Builds the default scene once on every thread, keeping the best time (the all-threads
    /// device is created by the first call, untimed).
    pub(super) fn build_pass_threads(&mut self) -> Result<()> {
        let device = match &mut self.device_threads {
            Some(d) => d,
            slot => slot.insert(crate::embree::EmbreeDevice::with_config("verbose=0")?),
        };
        let t0 = std::time::Instant::now();
        let s = crate::embree::EmbreeScene::from_mesh(&*device, &self.mesh, false)?;
        self.build_ms[2] = self.build_ms[2].min(t0.elapsed().as_secs_f64() * 1e3);
        drop(s);
        Ok(())
    }

    /// Best build times, ms: `[default, robust]` on one thread, default on all threads.
    pub(super) fn build_ms(&self) -> [f64; 3] {
        self.build_ms
    }

    /// Whether Embree gives a defined answer for `ray` ([`crate::embree::takes_ray`]); every
    /// side is timed on these rays only.
    pub(super) fn take(ray: &Ray) -> bool {
        crate::embree::takes_ray(ray)
    }

    /// The two scenes' queries of kind `query` (hit or miss), `[default, robust]`.
    pub(super) fn queries(&self, query: Query) -> Vec<HitQuery<'_>> {
        self.scenes
            .iter()
            .map(|s| match query {
                Query::Closest => {
                    Box::new(move |r: &Ray| s.intersect_ray(r).is_some()) as HitQuery<'_>
                }
                Query::Any => Box::new(move |r: &Ray| s.occluded_ray(r)) as HitQuery<'_>,
            })
            .collect()
    }

    /// The two scenes' closest hits (`rtcIntersect1`, untimed), `[default, robust]`, as the
    /// cross-check judges them.
    pub(super) fn closest(&self, ray: &Ray) -> Vec<Option<crate::crosscheck::judge::Answer>> {
        self.scenes
            .iter()
            .map(|s| crate::crosscheck::judge::Answer::of_embree(s, ray))
            .collect()
    }

    /// Whether the two scenes occlude `ray` (`rtcOccluded1`, untimed), `[default, robust]`.
    pub(super) fn occluded(&self, ray: &Ray) -> Vec<bool> {
        self.scenes.iter().map(|s| s.occluded_ray(ray)).collect()
    }

    /// Queries of kind `query` by Embree's packet API (closest hits: `rtcIntersect8/16`; any
    /// hit: `rtcOccluded8/16`), `[default by 8, default by 16, robust by 8, robust by 16]`.
    pub(super) fn packet_queries(&self, query: Query) -> Vec<BatchQuery<'_>> {
        let count = move |s: &crate::embree::EmbreeScene, rays: &[Ray], wide: bool| {
            let mut hits = 0;
            let mut hit = |_: usize, h: bool| hits += usize::from(h);
            match (query, wide) {
                (Query::Closest, true) => {
                    s.intersect_packets::<16>(rays, |i, h| hit(i, h.is_some()))
                }
                (Query::Closest, false) => {
                    s.intersect_packets::<8>(rays, |i, h| hit(i, h.is_some()))
                }
                (Query::Any, true) => s.occluded_packets::<16>(rays, hit),
                (Query::Any, false) => s.occluded_packets::<8>(rays, hit),
            }
            hits
        };
        self.scenes
            .iter()
            .flat_map(|s| {
                [false, true].map(move |wide| {
                    Box::new(move |rays: &[Ray]| count(s, rays, wide)) as BatchQuery<'_>
                })
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
    pub(super) fn build_pass_threads(&mut self) -> Result<()> {
        Ok(())
    }
    pub(super) fn build_ms(&self) -> [f64; 3] {
        [f64::NAN; 3]
    }
    pub(super) fn take(_ray: &Ray) -> bool {
        true
    }
    pub(super) fn queries(&self, _query: Query) -> Vec<HitQuery<'_>> {
        Vec::new()
    }
    pub(super) fn closest(&self, _ray: &Ray) -> Vec<Option<crate::crosscheck::judge::Answer>> {
        Vec::new()
    }
    pub(super) fn occluded(&self, _ray: &Ray) -> Vec<bool> {
        Vec::new()
    }
    pub(super) fn packet_queries(&self, _query: Query) -> Vec<BatchQuery<'_>> {
        Vec::new()
    }
}
