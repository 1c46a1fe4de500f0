//! A triangle mesh with its 8-wide BVH, owned (std), for the frontend's tools: closest-hit and
//! any-hit queries with any triangle intersector variant, on the widest SIMD level the CPU has
//! ([`crate::simd`]).

use crate::error::{Error, Result};
use crate::obj::ObjMesh;
use crate::pages::PageArray;
use halfray_core::Ray;
use halfray_core::bvh::wide::{Bvh8, LeafGroup, WideNode, binary_options, group_capacity};
use halfray_core::bvh::{
    BuildJob, BuildOptions, Bvh, BvhError, BvhNode, JobPart, PrimRef, index_capacity,
    node_capacity, scratch_capacity,
};
use halfray_core::mesh::TriangleMesh;
use halfray_core::prelude::*;
use halfray_core::query::{Query, QueryError, QueryStack, TraversalStats, Triangles};
use halfray_core::simd_level::{Portable, SimdLevel};
use halfray_core::triangle::{TriangleHit, TriangleVariant, VariantVisitor};

/// The wide BVH with owned storage.
pub type VecBvh8 = Bvh8<PageArray<WideNode<8>>, PageArray<LeafGroup>>;
/// The binary BVH with owned storage (nodes on huge pages, [`PageArray`]).
pub type VecBvh = Bvh<PageArray<BvhNode>, Vec<u32>>;

/// The node storage and scratch of a build over `n` triangles, on huge pages where the OS
/// gives them ([`PageArray`]), untouched until the build writes them
/// ([`PageArray::zeroed`]): the node array is sized for the worst case (`2n − 1` nodes, 64
/// bytes per triangle) of which the build writes the nodes it makes (a tree for the collapse
/// stops at small leaves and writes about a sixth), the scratch is 32 bytes per triangle, each
/// written once. The builder reads no node or record it has not written (nodes past its
/// node count are not part of the tree).
fn build_storage(n: usize) -> (PageArray<BvhNode>, PageArray<PrimRef>) {
    (
        PageArray::zeroed(node_capacity(n)),
        PageArray::zeroed(scratch_capacity(n)),
    )
}

/// Builds the binary BVH over `mesh` (binned SAH, `options`) with the scratch builder (a
/// temporary array of 32 bytes per triangle, freed on return), compiled for AVX2 + FMA when
/// the CPU has them, as the queries are ([`crate::simd::x86_avx2_fma`]). The same tree either
/// way: the builder's arithmetic is plain `f32` operations, which the wider instructions round
/// alike (Rust never contracts `a·b + c` into a fused multiply-add).
pub fn build_binary(
    mesh: &TriangleMesh<'_>,
    options: &BuildOptions,
) -> std::result::Result<VecBvh, BvhError> {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::x86_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked at run time), the only requirement of
        // calling a `#[target_feature(enable = "avx2,fma")]` fn.
        return unsafe { build_binary_avx2_fma(mesh, options) };
    }
    build_binary_here(mesh, options)
}

/// [`build_binary`]'s AVX2 + FMA path: the core's builder is `#[inline(always)]` down to its
/// per-primitive loops, so it compiles into this function with its features.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn build_binary_avx2_fma(
    mesh: &TriangleMesh<'_>,
    options: &BuildOptions,
) -> std::result::Result<VecBvh, BvhError> {
    build_binary_here(mesh, options)
}

/// [`build_binary`] compiled with the target features of the function it is inlined into.
#[inline(always)]
fn build_binary_here(
    mesh: &TriangleMesh<'_>,
    options: &BuildOptions,
) -> std::result::Result<VecBvh, BvhError> {
    let n = mesh.len();
    let (nodes, mut scratch) = build_storage(n);
    Bvh::build_with_scratch(
        mesh,
        nodes,
        vec![0u32; index_capacity(n)],
        &mut scratch,
        options,
    )
}

/// Meshes below this many triangles are built on one thread: below it, splitting the work
/// costs more than it saves.
pub const PARALLEL_BUILD_MIN: usize = 20_000;

/// [`build_binary`] on rayon's threads: the core builds the top of the tree and hands out
/// subtrees of at most `n / (4·threads)` triangles ([`Bvh::build_in_jobs`]), which the pool
/// builds largest first; the same tree as [`build_binary`]. One thread, or fewer than
/// [`PARALLEL_BUILD_MIN`] triangles: [`build_binary`] itself. With AVX2 and FMA the top and
/// every subtree run compiled for them, as [`build_binary`] does.
pub fn build_binary_parallel(
    mesh: &TriangleMesh<'_>,
    options: &BuildOptions,
) -> std::result::Result<VecBvh, BvhError> {
    let n = mesh.len();
    let threads = rayon::current_num_threads();
    if threads <= 1 || n < PARALLEL_BUILD_MIN {
        return build_binary(mesh, options);
    }
    #[cfg(target_arch = "x86_64")]
    if crate::simd::x86_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked at run time), the only requirement of
        // calling a `#[target_feature(enable = "avx2,fma")]` fn.
        return unsafe { build_binary_parallel_avx2_fma(mesh, options, threads) };
    }
    build_binary_parallel_here(mesh, options, threads)
}

/// [`build_binary_parallel`]'s AVX2 + FMA path (the top of the tree; the subtrees through
/// [`build_part`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn build_binary_parallel_avx2_fma(
    mesh: &TriangleMesh<'_>,
    options: &BuildOptions,
    threads: usize,
) -> std::result::Result<VecBvh, BvhError> {
    build_binary_parallel_here(mesh, options, threads)
}

/// [`build_binary_parallel`] on `threads` threads, compiled with the target features of the
/// function it is inlined into.
#[inline(always)]
fn build_binary_parallel_here(
    mesh: &TriangleMesh<'_>,
    options: &BuildOptions,
    threads: usize,
) -> std::result::Result<VecBvh, BvhError> {
    let n = mesh.len();
    let mut jobs = vec![BuildJob::EMPTY; 16 * threads];
    let (nodes, mut scratch) = build_storage(n);
    Bvh::build_in_jobs(
        mesh,
        nodes,
        vec![0u32; index_capacity(n)],
        &mut scratch,
        &mut jobs,
        n / (4 * threads),
        options,
        |parts| {
            use rayon::prelude::*;
            let mut parts: Vec<JobPart<'_>> = parts.collect();
            parts.sort_by_key(|p| std::cmp::Reverse(p.primitives()));
            parts.into_par_iter().for_each(build_part);
        },
    )
}

/// Builds one subtree of [`build_binary_parallel`] on the calling thread, compiled for AVX2
/// and FMA where the CPU has them (a closure cannot carry target features).
fn build_part(part: JobPart<'_>) {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::x86_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked at run time), the only requirement of
        // calling a `#[target_feature(enable = "avx2,fma")]` fn.
        return unsafe { build_part_avx2_fma(part) };
    }
    part.build();
}

/// [`build_part`]'s AVX2 + FMA path: [`JobPart::build`] is inlined down to its loops.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn build_part_avx2_fma(part: JobPart<'_>) {
    part.build();
}

/// Collapses `binary` (built over `mesh`, in any storage) into an 8-wide BVH in one walk
/// ([`Bvh8::from_binary_in`]) into storage of the bounds it needs, untouched until the
/// collapse writes it ([`PageArray::zeroed`]): the collapse writes every node and group the
/// tree uses (unused lanes as [`LeafGroup::EMPTY`]'s); the pages past them are never touched,
/// so they cost neither time nor resident memory.
pub fn build_wide<N: AsRef<[BvhNode]>, I: AsRef<[u32]>>(
    mesh: &TriangleMesh<'_>,
    binary: &Bvh<N, I>,
) -> std::result::Result<VecBvh8, BvhError> {
    Bvh8::from_binary_in(
        binary,
        mesh,
        PageArray::zeroed(VecBvh8::node_bound_for(binary)),
        PageArray::zeroed(group_capacity(binary.indices().len())),
    )
}

/// A mesh ready for ray queries.
pub struct MeshAccel {
    /// The mesh.
    pub mesh: ObjMesh,
    wide: VecBvh8,
}

impl MeshAccel {
    /// Builds the BVH over `mesh` (binned SAH with default options, collapsed to 8 wide).
    pub fn new(mesh: ObjMesh) -> Result<Self> {
        let tri = TriangleMesh::new(&mesh.positions, &mesh.triangles);
        let wide = build_binary_parallel(&tri, &binary_options(BuildOptions::default()))
            .and_then(|b| build_wide(&tri, &b))
            .map_err(Error::Bvh)?;
        Ok(Self { mesh, wide })
    }

    /// The wide BVH.
    pub fn bvh(&self) -> &VecBvh8 {
        &self.wide
    }

    /// The mesh as the core's queries take it.
    pub fn triangles(&self) -> TriangleMesh<'_> {
        TriangleMesh::new(&self.mesh.positions, &self.mesh.triangles)
    }

    /// Closest hit with `isect`: `(triangle index, hit)`, with traversal statistics added to
    /// `stats` when given.
    #[inline]
    pub fn closest<'s, I: TriangleIntersector>(
        &self,
        isect: &I,
        ray: &Ray,
        stats: impl Into<Option<&'s mut TraversalStats>>,
    ) -> Option<(u32, TriangleHit)> {
        closest_simd(&self.wide, &self.triangles(), isect, ray, stats.into())
    }

    /// Whether anything is hit in the ray's interval.
    pub fn any<I: TriangleIntersector>(&self, isect: &I, ray: &Ray) -> bool {
        any_simd(&self.wide, &self.triangles(), isect, ray).is_some()
    }

    /// Closest hit with a variant chosen at run time.
    pub fn closest_variant(&self, v: TriangleVariant, ray: &Ray) -> Option<(u32, TriangleHit)> {
        struct Closest<'a>(&'a MeshAccel, &'a Ray);
        impl VariantVisitor for Closest<'_> {
            type Output = Option<(u32, TriangleHit)>;
            fn visit<I: TriangleIntersector>(self, isect: &I) -> Self::Output {
                self.0.closest(isect, self.1, None)
            }
        }
        v.visit(Closest(self, ray))
    }

    /// The closest hits of `rays` with a variant chosen at run time, by the batch query
    /// ([`closest_batch_simd`]): entry `i` is [`MeshAccel::closest_variant`] of `rays[i]`, bit
    /// for bit.
    pub fn closest_variant_batch(&self, v: TriangleVariant, rays: &[Ray]) -> Vec<Answer> {
        struct Batch<'a>(&'a MeshAccel, &'a [Ray]);
        impl VariantVisitor for Batch<'_> {
            type Output = Vec<Answer>;
            fn visit<I: TriangleIntersector>(self, isect: &I) -> Vec<Answer> {
                self.0.closest_batch(isect, self.1, None)
            }
        }
        v.visit(Batch(self, rays))
    }

    /// The closest hits of `rays` with `isect`, by the batch query ([`closest_batch_simd`]:
    /// coherent rays walked in packets): entry `i` is [`MeshAccel::closest`] of `rays[i]`, bit
    /// for bit. `stats`, when given, is added to (a packet's node tests counted once).
    pub fn closest_batch<I: TriangleIntersector>(
        &self,
        isect: &I,
        rays: &[Ray],
        mut stats: Option<&mut TraversalStats>,
    ) -> Vec<Answer> {
        let mut out = vec![None; rays.len()];
        let mesh = self.triangles();
        // `out` has `rays.len()` entries, the batch query's only refusal; were it refused,
        // the single-ray query gives the same answers.
        let batch = closest_batch_simd(
            &self.wide,
            &mesh,
            isect,
            rays,
            &mut out,
            stats.as_deref_mut(),
        );
        if batch.is_err() {
            return rays
                .iter()
                .map(|r| self.closest(isect, r, stats.as_deref_mut()))
                .collect();
        }
        out
    }

    /// Whether anything is hit in each of `rays`' intervals, by the batch query
    /// ([`any_batch_simd`]: coherent rays, as shadow rays towards one light, walked in
    /// packets): entry `i` is [`MeshAccel::any`] of `rays[i]`. `stats`, when given, is added
    /// to (a packet's node tests counted once).
    pub fn any_batch<I: TriangleIntersector>(
        &self,
        isect: &I,
        rays: &[Ray],
        stats: Option<&mut TraversalStats>,
    ) -> Vec<bool> {
        let mut out = vec![None; rays.len()];
        // `out` has `rays.len()` entries, the batch query's only refusal; were it refused,
        // the single-ray query gives the same answers.
        match any_batch_simd(&self.wide, &self.triangles(), isect, rays, &mut out, stats) {
            Ok(()) => out.iter().map(Option::is_some).collect(),
            Err(_) => rays.iter().map(|r| self.any(isect, r)).collect(),
        }
    }

    /// Any hit with a variant chosen at run time.
    pub fn any_variant(&self, v: TriangleVariant, ray: &Ray) -> bool {
        struct Any<'a>(&'a MeshAccel, &'a Ray);
        impl VariantVisitor for Any<'_> {
            type Output = bool;
            fn visit<I: TriangleIntersector>(self, isect: &I) -> bool {
                self.0.any(isect, self.1)
            }
        }
        v.visit(Any(self, ray))
    }
}

thread_local! {
    /// One traversal stack per thread, kept across rays (creating one writes 3.5 KiB). Taken
    /// out for a query and put back after it ([`with_stack`]).
    static STACK: std::cell::Cell<Option<Box<QueryStack>>> = const { std::cell::Cell::new(None) };
}

/// Runs `f` on this thread's kept stack: taken out of the thread-local slot and put back, so
/// the query's result is returned by `f` directly (a `RefCell` borrow through
/// `LocalKey::with` returned it through a closure and copied it twice, ~15–25 ns per ray
/// measured, the copies stalling on store forwarding). A nested query (an intersector that
/// traces rays itself) finds the slot empty and uses a stack of its own.
#[inline(always)]
fn with_stack<R>(f: impl FnOnce(&mut QueryStack) -> R) -> R {
    let mut stack = STACK.take().unwrap_or_else(|| Box::new(QueryStack::new()));
    let r = f(&mut stack);
    STACK.set(Some(stack));
    r
}

/// One ray's closest hit: `(triangle index, hit)`.
pub type Answer = Option<(u32, TriangleHit)>;

/// The closest hit of `ray` in `bvh` over the triangles of `mesh` (the mesh the tree was
/// built over) with `isect`, compiled for AVX2 + FMA when the CPU has them
/// ([`crate::simd::x86_avx2_fma`]), for the baseline target otherwise, on this thread's kept
/// stack. Same answers either way: the core never fuses a multiply-add (its exactness
/// arguments need plain roundings) and Rust does not contract `a·b + c`, so the wider vectors
/// change only the speed.
#[inline]
pub fn closest_simd<I: TriangleIntersector>(
    bvh: &VecBvh8,
    mesh: &TriangleMesh<'_>,
    isect: &I,
    ray: &Ray,
    stats: Option<&mut TraversalStats>,
) -> Answer {
    on_widest_level(
        Closest(ray),
        Scene {
            bvh,
            leaf: Triangles::new(mesh, isect),
            stats,
        },
    )
}

/// The closest hits of `rays` into `out` (as many entries) by the batch query
/// ([`RayQuery::closest_hits`]: coherent rays walked in packets), on the widest SIMD level and
/// this thread's kept stack: `out[i]` is [`closest_simd`] of `rays[i]`, bit for bit. `stats`,
/// when given, is added to (a packet's node tests counted once).
///
/// # Errors
///
/// [`QueryError::LengthMismatch`] when `out` has not `rays.len()` entries (nothing written).
#[inline]
pub fn closest_batch_simd<I: TriangleIntersector>(
    bvh: &VecBvh8,
    mesh: &TriangleMesh<'_>,
    isect: &I,
    rays: &[Ray],
    out: &mut [Answer],
    stats: Option<&mut TraversalStats>,
) -> std::result::Result<(), QueryError> {
    let leaf = Triangles::new(mesh, isect);
    on_widest_level(ClosestBatch(rays, out), Scene { bvh, leaf, stats })
}

/// Any hits of `rays` into `out` (as many entries) by the batch query
/// ([`RayQuery::any_hits`]: coherent rays, as shadow rays towards one light, walked in
/// packets), on the widest SIMD level and this thread's kept stack: `out[i]` is a hit exactly
/// when [`any_simd`] of `rays[i]` is, and a hit of `rays[i]` (in a packet, perhaps another
/// triangle than [`any_simd`]'s). `stats`, when given, is added to (a packet's node tests
/// counted once).
///
/// # Errors
///
/// [`QueryError::LengthMismatch`] when `out` has not `rays.len()` entries (nothing written).
#[inline]
pub fn any_batch_simd<I: TriangleIntersector>(
    bvh: &VecBvh8,
    mesh: &TriangleMesh<'_>,
    isect: &I,
    rays: &[Ray],
    out: &mut [Answer],
    stats: Option<&mut TraversalStats>,
) -> std::result::Result<(), QueryError> {
    let leaf = Triangles::new(mesh, isect);
    on_widest_level(AnyBatch(rays, out), Scene { bvh, leaf, stats })
}

/// Any hit of `ray`, on the widest SIMD level, as [`closest_simd`].
#[inline]
pub fn any_simd<I: TriangleIntersector>(
    bvh: &VecBvh8,
    mesh: &TriangleMesh<'_>,
    isect: &I,
    ray: &Ray,
) -> Answer {
    let stats = None;
    on_widest_level(
        Any(ray),
        Scene {
            bvh,
            leaf: Triangles::new(mesh, isect),
            stats,
        },
    )
}

/// What every query of this module walks: the tree, its triangles' leaf test and the
/// statistics to add to.
struct Scene<'a, I> {
    bvh: &'a VecBvh8,
    leaf: Triangles<'a, I>,
    stats: Option<&'a mut TraversalStats>,
}

/// One query of a [`Scene`] at SIMD level `level` on a caller's stack: [`Closest`], [`Any`],
/// [`ClosestBatch`], [`AnyBatch`].
trait Job<I> {
    type Out;
    fn run<L: SimdLevel>(self, level: L, scene: Scene<'_, I>, stack: &mut QueryStack) -> Self::Out;
}

/// [`closest_simd`]'s query.
struct Closest<'r>(&'r Ray);
/// [`any_simd`]'s query.
struct Any<'r>(&'r Ray);
/// [`closest_batch_simd`]'s query.
struct ClosestBatch<'r>(&'r [Ray], &'r mut [Answer]);
/// [`any_batch_simd`]'s query.
struct AnyBatch<'r>(&'r [Ray], &'r mut [Answer]);

impl<I: TriangleIntersector> Job<I> for Closest<'_> {
    type Out = Answer;
    #[inline(always)]
    fn run<L: SimdLevel>(self, level: L, mut s: Scene<'_, I>, stack: &mut QueryStack) -> Answer {
        let ctx = &mut Query::new().on(level).stack(stack).stats(s.stats);
        s.bvh.closest_hit(self.0, &mut s.leaf, ctx)
    }
}

impl<I: TriangleIntersector> Job<I> for Any<'_> {
    type Out = Answer;
    #[inline(always)]
    fn run<L: SimdLevel>(self, level: L, mut s: Scene<'_, I>, stack: &mut QueryStack) -> Answer {
        let ctx = &mut Query::new().on(level).stack(stack).stats(s.stats);
        s.bvh.any_hit(self.0, &mut s.leaf, ctx)
    }
}

impl<I: TriangleIntersector> Job<I> for ClosestBatch<'_> {
    type Out = std::result::Result<(), QueryError>;
    #[inline(always)]
    fn run<L: SimdLevel>(self, level: L, mut s: Scene<'_, I>, stack: &mut QueryStack) -> Self::Out {
        let ctx = &mut Query::new().on(level).stack(stack).stats(s.stats);
        s.bvh.closest_hits(self.0, &mut s.leaf, ctx, self.1)
    }
}

impl<I: TriangleIntersector> Job<I> for AnyBatch<'_> {
    type Out = std::result::Result<(), QueryError>;
    #[inline(always)]
    fn run<L: SimdLevel>(self, level: L, mut s: Scene<'_, I>, stack: &mut QueryStack) -> Self::Out {
        let ctx = &mut Query::new().on(level).stack(stack).stats(s.stats);
        s.bvh.any_hits(self.0, &mut s.leaf, ctx, self.1)
    }
}

/// Runs `job` on `scene` at the widest SIMD level the CPU has, on this thread's kept stack.
#[inline(always)]
fn on_widest_level<I, J: Job<I>>(job: J, scene: Scene<'_, I>) -> J::Out {
    #[cfg(target_arch = "x86_64")]
    if let Some(level) = crate::simd::avx2_fma() {
        // SAFETY: the token exists, so the CPU supports AVX2 and FMA (checked at run time),
        // the only requirement of calling a `#[target_feature(enable = "avx2,fma")]` fn.
        return unsafe { on_avx2_fma(level, job, scene) };
    }
    with_stack(|stack| job.run(Portable, scene, stack))
}

/// [`on_widest_level`]'s AVX2 + FMA path: the whole query, the thread's stack included, is
/// one function compiled for those features. The `with_stack` closure is written here because
/// a closure takes the target features of the function it is written in: one written in a
/// shared helper would compile the walk for the baseline target, its SIMD kernels called out
/// of line. ([`Job::run`] is `#[inline(always)]`, so the walk is inlined into it.)
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn on_avx2_fma<I, J: Job<I>>(
    level: halfray_core::simd_level::Avx2Fma,
    job: J,
    scene: Scene<'_, I>,
) -> J::Out {
    with_stack(|stack| job.run(level, scene, stack))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh_tools::generate::{Kind, generate};

    /// The binary build compiled for AVX2 + FMA ([`build_binary`] on a CPU with them) writes the
    /// tree the baseline build writes, node for node and index for index, on each generated
    /// corpus kind (small sizes) with the default and the wide tree's options, and the wide trees
    /// collapsed from both are equal. Compared through `Debug`, which prints each `f32` as its
    /// shortest round-trip form (`-0.0` and `0.0` apart), so equal text is equal bits. On a CPU
    /// without AVX2 and FMA the comparison cannot run: the skip is recorded
    /// ([`crate::skips::record_skip`]; with `HALFRAY_REQUIRE_AVX2` set, it fails).
    #[test]
    fn the_avx2_build_writes_the_baseline_tree() {
        if !crate::simd::x86_avx2_fma() {
            assert!(
                std::env::var_os("HALFRAY_REQUIRE_AVX2").is_none(),
                "HALFRAY_REQUIRE_AVX2 is set but the CPU reports no AVX2+FMA"
            );
            crate::skips::record_skip(
                "SKIPPED halfray accel::tests::the_avx2_build_writes_the_baseline_tree: no AVX2+FMA on this CPU",
            );
            return;
        }
        let kinds = [
            (Kind::Sphere, 24),
            (Kind::Terrain, 40),
            (Kind::Beams, 300),
            (Kind::Room, 12),
            (Kind::Scatter, 200),
            (Kind::Far, 16),
        ];
        let defaults = BuildOptions::default();
        let text = |x: &dyn std::fmt::Debug| format!("{x:?}");
        for (kind, n) in kinds {
            let g = generate(kind, 7, Some(n)).unwrap();
            let mesh = TriangleMesh::new(&g.positions, &g.triangles);
            assert!(mesh.len() > 1_000, "{kind:?}: {} triangles", mesh.len());
            for options in [defaults, binary_options(defaults)] {
                let base = build_binary_here(&mesh, &options).unwrap();
                let avx2 = build_binary(&mesh, &options).unwrap();
                assert_eq!(text(&base.nodes()), text(&avx2.nodes()), "{kind:?}");
                assert_eq!(base.indices(), avx2.indices(), "{kind:?}");
                let (wa, wb) = (
                    build_wide(&mesh, &base).unwrap(),
                    build_wide(&mesh, &avx2).unwrap(),
                );
                assert_eq!(text(&wa.nodes()), text(&wb.nodes()), "{kind:?}");
                assert_eq!(text(&wa.groups()), text(&wb.groups()), "{kind:?}");
                // The build in jobs (two threads' job size), baseline and AVX2: the one-thread
                // tree with another node numbering, so the same collapsed tree.
                let jobs_base = build_binary_parallel_here(&mesh, &options, 2).unwrap();
                // SAFETY: the CPU supports AVX2 and FMA (checked at the top).
                let jobs_avx2 =
                    unsafe { build_binary_parallel_avx2_fma(&mesh, &options, 2) }.unwrap();
                assert_eq!(jobs_base.indices(), avx2.indices(), "{kind:?}");
                assert_eq!(jobs_avx2.indices(), avx2.indices(), "{kind:?}");
                for jobs in [jobs_base, jobs_avx2] {
                    let wj = build_wide(&mesh, &jobs).unwrap();
                    assert_eq!(text(&wj.nodes()), text(&wb.nodes()), "{kind:?}");
                    assert_eq!(text(&wj.groups()), text(&wb.groups()), "{kind:?}");
                }
            }
        }
    }
}
