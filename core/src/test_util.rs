//! Helpers shared by the unit tests of the core (compiled only for `cargo test`).

use crate::bvh::wide::{LeafGroup, WideBvh, WideNode, group_capacity};
use crate::bvh::{BuildOptions, Bvh, BvhError, BvhNode, index_capacity, node_capacity};
use crate::grid::{Grid, GridError, GridOptions, GridPlan};
use crate::kdtree::{KdBuildOptions, KdNode, KdRef, KdTree, KdTreeError};
use crate::mesh::{PrimitiveSource, TriangleMesh};
use crate::query::{Query, RayQuery, Stack, Triangles};
use crate::ray::Ray;
use crate::simd_level::SimdLevel;
use crate::triangle::{TriangleHit, TriangleIntersector, Watertight};
use glam::{Vec3, vec3};
use std::vec;
use std::vec::Vec;

/// Floats that break arithmetic: NaN, the infinities, both zeros, the extremes of the normal
/// range, subnormals, and a few ordinary values for contrast.
pub const SPECIAL_F32: [f32; 14] = [
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    0.0,
    -0.0,
    f32::MAX,
    -f32::MAX,
    -3.0e38,
    f32::MIN_POSITIVE,
    1.0e-40,
    1.0e-45,
    1.0,
    -1.0,
    0.5,
];

/// One of [`SPECIAL_F32`], drawn with [`lcg`].
pub fn special_f32(state: &mut u64) -> f32 {
    SPECIAL_F32[(lcg(state) * SPECIAL_F32.len() as f32) as usize % SPECIAL_F32.len()]
}

/// With probability `special` one of [`SPECIAL_F32`], otherwise uniform in
/// `[-width/2, width/2)`; drawn with [`lcg`].
pub fn mixed_f32(state: &mut u64, special: f32, width: f32) -> f32 {
    if lcg(state) < special {
        special_f32(state)
    } else {
        (lcg(state) - 0.5) * width
    }
}

/// A 64-bit LCG (Knuth's MMIX constants) giving `f32` in `[0, 1)` with 24 random bits.
pub fn lcg(state: &mut u64) -> f32 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 40) as f32) / ((1u64 << 24) as f32)
}

/// A point with integer coordinates drawn uniformly from `[-n, n]` (`n` a whole number).
pub fn grid_point(s: &mut u64, n: f32) -> Vec3 {
    let mut g = || (lcg(s) * (2.0 * n + 1.0)).floor() - n;
    vec3(g(), g(), g())
}

/// A random unit vector (rejection sampling in the unit ball).
pub fn unit_vec(s: &mut u64) -> Vec3 {
    loop {
        let v = Vec3::new(lcg(s) * 2.0 - 1.0, lcg(s) * 2.0 - 1.0, lcg(s) * 2.0 - 1.0);
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

/// A seeded generator over [`lcg`] for the acceleration structures' tests: the same
/// sequence as calling [`lcg`] on the state.
pub struct Lcg(pub u64);

impl Lcg {
    /// The next `f32` in `[0, 1)` ([`lcg`]).
    pub fn f(&mut self) -> f32 {
        lcg(&mut self.0)
    }

    /// A vector with components drawn in x, y, z order from `[-s/2, s/2)`.
    pub fn v(&mut self, s: f32) -> Vec3 {
        Vec3::new(self.f() - 0.5, self.f() - 0.5, self.f() - 0.5) * s
    }
}

/// `n` random triangles from [`Lcg`]`(seed)`, three vertices of their own each: triangle
/// `i` is `[3i, 3i + 1, 3i + 2]` around a centre `v(spread)`, each vertex the centre plus
/// `v(size)` (centre first, then the three offsets, for every triangle in turn).
pub fn lcg_soup(n: usize, seed: u64, spread: f32, size: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut r = Lcg(seed);
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for i in 0..n {
        let c = r.v(spread);
        pos.extend([c + r.v(size), c + r.v(size), c + r.v(size)]);
        let b = 3 * i as u32;
        tris.push([b, b + 1, b + 2]);
    }
    (pos, tris)
}

/// The tests' oracle for the acceleration structures: [`Watertight`] on every triangle of
/// `mesh` in index order (triangles with an index out of range skipped), keeping the
/// smallest `t`; strict `<`, so of equal `t` the smaller index wins.
pub fn brute_watertight(mesh: &TriangleMesh<'_>, ray: &Ray) -> Option<(u32, TriangleHit)> {
    let mut best: Option<(u32, TriangleHit)> = None;
    for i in 0..mesh.len() {
        let Some(v) = mesh.triangle(i) else { continue };
        if let Some(h) = Watertight.intersect(ray, &v)
            && best.is_none_or(|(_, b)| h.t < b.t)
        {
            best = Some((i as u32, h));
        }
    }
    best
}

/// The box queries' oracle, written from their contract and sharing no code with
/// [`Aabb`](crate::aabb::Aabb) or the trees: whether triangle `v` overlaps the closed box
/// `[lo, hi]`. A triangle with a non-finite coordinate overlaps nothing (its bounds are
/// unusable, so no tree holds it); otherwise it overlaps exactly when, on every axis, the
/// closed interval from the smallest to the largest of its three vertex coordinates meets
/// `[lo, hi]` — compared in `f64`, so a NaN bound meets nothing.
pub fn triangle_meets_box(v: &[Vec3; 3], lo: Vec3, hi: Vec3) -> bool {
    let coords = v.map(|p| [f64::from(p.x), f64::from(p.y), f64::from(p.z)]);
    if !coords.iter().flatten().all(|c| c.is_finite()) {
        return false;
    }
    let (lo, hi) = (lo.to_array(), hi.to_array());
    (0..3).all(|axis| {
        // Finite coordinates (checked above): `min`/`max` are the plain order.
        let [a, b, c] = coords.map(|p| p[axis]);
        a.min(b).min(c) <= f64::from(hi[axis]) && f64::from(lo[axis]) <= a.max(b).max(c)
    })
}

/// Brute force for the box queries: every triangle of `mesh` (in index order; missing
/// vertices skipped) that [`triangle_meets_box`] the box `[lo, hi]`.
pub fn brute_box(mesh: &TriangleMesh<'_>, lo: Vec3, hi: Vec3) -> Vec<u32> {
    (0..mesh.len())
        .filter(|&i| {
            mesh.triangle(i)
                .is_some_and(|v| triangle_meets_box(&v, lo, hi))
        })
        .map(|i| i as u32)
        .collect()
}

/// A binary BVH in vectors.
pub type VecBvh = Bvh<Vec<BvhNode>, Vec<u32>>;

/// [`Bvh::build`] over `src` into full-capacity vectors.
pub fn vec_bvh<S: PrimitiveSource + ?Sized>(
    src: &S,
    opts: &BuildOptions,
) -> Result<VecBvh, BvhError> {
    let n = src.primitive_count();
    Bvh::build(
        src,
        vec![BvhNode::EMPTY; node_capacity(n)],
        vec![0u32; index_capacity(n)],
        opts,
    )
}

/// A wide tree (`W` = 8 or 4) in vectors.
pub type VecWide<const W: usize> = WideBvh<W, Vec<WideNode<W>>, Vec<LeafGroup>>;

/// [`WideBvh::from_binary`] of `binary` (built over `mesh`) into full-capacity vectors.
pub fn vec_wide<const W: usize>(
    binary: &VecBvh,
    mesh: &TriangleMesh<'_>,
) -> Result<VecWide<W>, BvhError> {
    let n = mesh.len();
    WideBvh::from_binary(
        binary,
        mesh,
        vec![WideNode::EMPTY; crate::bvh::wide::node_capacity(n)],
        vec![LeafGroup::EMPTY; group_capacity(n)],
    )
}

/// A grid in vectors.
pub type VecGrid = Grid<Vec<u32>, Vec<u32>>;

/// [`GridPlan::new`] then [`Grid::build`] of `mesh` with `options`, into vectors of exactly
/// the planned sizes filled with `u32::MAX` (so a slot the build forgets to write shows).
pub fn vec_grid(mesh: &TriangleMesh<'_>, options: &GridOptions) -> Result<VecGrid, GridError> {
    let plan = GridPlan::new(mesh, options)?;
    Grid::build(
        mesh,
        &plan,
        vec![u32::MAX; plan.required_offsets()],
        vec![u32::MAX; plan.required_references()],
    )
}

/// A kd-tree in vectors.
pub type VecKd = KdTree<Vec<KdNode>, Vec<u32>>;

/// [`KdTree::build`] of `src` with `options` into `nodes` nodes and `refs` references (filled
/// with `u32::MAX`) and as many scratch references.
pub fn vec_kd_sized<S: PrimitiveSource + ?Sized>(
    src: &S,
    nodes: usize,
    refs: usize,
    options: &KdBuildOptions,
) -> Result<VecKd, KdTreeError> {
    let mut scratch = vec![KdRef::EMPTY; refs];
    KdTree::build(
        src,
        vec![KdNode::EMPTY; nodes],
        vec![u32::MAX; refs],
        &mut scratch,
        options,
    )
}

/// [`vec_kd_sized`] at full capacity ([`crate::kdtree::node_capacity`], at least one node,
/// and [`crate::kdtree::reference_capacity`] of the primitive count).
pub fn vec_kd<S: PrimitiveSource + ?Sized>(
    src: &S,
    options: &KdBuildOptions,
) -> Result<VecKd, KdTreeError> {
    let n = src.primitive_count();
    vec_kd_sized(
        src,
        crate::kdtree::node_capacity(n).max(1),
        crate::kdtree::reference_capacity(n),
        options,
    )
}

/// The closest hit of `ray` in `accel` over [`Watertight`] triangles of `mesh` with the
/// context `ctx`: the query call the structures' tests make (the code under test, not an
/// oracle).
pub fn closest_watertight_in<A, L, S>(
    accel: &A,
    mesh: &TriangleMesh<'_>,
    ray: &Ray,
    ctx: &mut Query<'_, L, S>,
) -> S::Out<(u32, TriangleHit)>
where
    A: RayQuery + ?Sized,
    L: SimdLevel,
    S: Stack,
{
    accel.closest_hit(ray, &mut Triangles::new(mesh, &Watertight), ctx)
}

/// [`closest_watertight_in`] with a fresh default context.
pub fn closest_watertight<A: RayQuery + ?Sized>(
    accel: &A,
    mesh: &TriangleMesh<'_>,
    ray: &Ray,
) -> Option<(u32, TriangleHit)> {
    closest_watertight_in(accel, mesh, ray, &mut Query::new())
}

/// The any hit of `ray` in `accel` over [`Watertight`] triangles of `mesh`, with a fresh
/// default context.
pub fn any_watertight<A: RayQuery + ?Sized>(
    accel: &A,
    mesh: &TriangleMesh<'_>,
    ray: &Ray,
) -> Option<(u32, TriangleHit)> {
    accel.any_hit(
        ray,
        &mut Triangles::new(mesh, &Watertight),
        &mut Query::new(),
    )
}

/// The AVX2+FMA level for the test named `test`, when this CPU has it. Otherwise the skip is
/// recorded once per test — `SKIPPED test: no AVX2+FMA on this CPU` on stderr and appended to
/// the file `HALFRAY_SKIP_LOG` names (`scripts/test-all.sh` prints it after the tests, so CI
/// names every skipped test and why) — and the answer is `None`. When `HALFRAY_REQUIRE_AVX2`
/// is set (the script sets it when `/proc/cpuinfo` lists `avx2` and `fma`), a missing level
/// fails the test instead: on such a CPU nothing may be skipped.
#[cfg(target_arch = "x86_64")]
pub fn avx2_or_skip(test: &'static str) -> Option<crate::simd::level::Avx2Fma> {
    let level = crate::simd::level::Avx2Fma::detect();
    if level.is_none() {
        assert!(
            std::env::var_os("HALFRAY_REQUIRE_AVX2").is_none(),
            "{test}: HALFRAY_REQUIRE_AVX2 is set but the CPU reports no AVX2+FMA"
        );
        record_skip(
            test,
            "no AVX2+FMA on this CPU: the AVX2 kernels cannot run here",
        );
    }
    level
}

/// Records (once per test name per process) that `test` skipped part of its checks, and why.
pub fn record_skip(test: &'static str, why: &str) {
    use std::io::Write;
    static SEEN: std::sync::Mutex<Vec<&'static str>> = std::sync::Mutex::new(Vec::new());
    let mut seen = SEEN
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if seen.contains(&test) {
        return;
    }
    seen.push(test);
    let line = std::format!("SKIPPED halfray-core {test}: {why}");
    std::eprintln!("{line}");
    if let Some(path) = std::env::var_os("HALFRAY_SKIP_LOG") {
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path);
        if let Ok(mut f) = file {
            let _ = writeln!(f, "{line}");
        }
    }
}

/// A source whose answers change between calls, against [`PrimitiveSource`]'s rule that they
/// are a function of the index (which the builders may not rely on for their safety): each
/// of the first `steady` calls answers `boxes[i]`; after that, `change(i, call)` decides
/// (`None`: still `boxes[i]`). An index at or beyond the count **panics** (plain slice
/// indexing, as a caller's source may), so a builder that asks for one fails the test.
pub struct Fickle<F: Fn(usize, u64) -> Option<crate::aabb::Aabb>> {
    /// The steady answers.
    pub boxes: Vec<crate::aabb::Aabb>,
    /// Calls answered steadily.
    pub steady: u64,
    /// The answer after them.
    pub change: F,
    /// Calls so far.
    pub calls: core::cell::Cell<u64>,
}

impl<F: Fn(usize, u64) -> Option<crate::aabb::Aabb>> PrimitiveSource for Fickle<F> {
    fn primitive_count(&self) -> usize {
        self.boxes.len()
    }

    fn primitive_bounds(&self, i: usize) -> crate::aabb::Aabb {
        let call = self.calls.get();
        self.calls.set(call + 1);
        let steady = self.boxes[i];
        if call < self.steady {
            steady
        } else {
            (self.change)(i, call).unwrap_or(steady)
        }
    }
}

/// Storage whose `AsRef` gives `a` until `flip` is set and `b` after (an A/B flash region
/// switched by a flag; safe code only): what a structure built over `a` sees once its
/// storage changed under it. `AsMut` always gives `a` (the build writes there).
pub struct Flip<T> {
    /// What the build writes and the structure sees first.
    pub a: Vec<T>,
    /// What the structure sees once `flip` is set.
    pub b: Vec<T>,
    /// The switch.
    pub flip: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl<T> Flip<T> {
    /// `a`, switching to `b` when the returned flag is set.
    pub fn new(a: Vec<T>, b: Vec<T>) -> (Self, std::sync::Arc<std::sync::atomic::AtomicBool>) {
        let flip = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        (
            Self {
                a,
                b,
                flip: flip.clone(),
            },
            flip,
        )
    }
}

impl<T> AsRef<[T]> for Flip<T> {
    fn as_ref(&self) -> &[T] {
        if self.flip.load(std::sync::atomic::Ordering::Relaxed) {
            &self.b
        } else {
            &self.a
        }
    }
}

/// The audit's case: boxes `[k, k + ½]³` for `k` in `0..n`, primitive 0's answer all-NaN
/// once every primitive has been asked once (a builder's second pass sees it unusable).
pub fn fickle_first(n: usize) -> Fickle<impl Fn(usize, u64) -> Option<crate::aabb::Aabb>> {
    Fickle {
        boxes: (0..n)
            .map(|k| crate::aabb::Aabb::new(Vec3::splat(k as f32), Vec3::splat(k as f32 + 0.5)))
            .collect(),
        steady: n as u64,
        change: |i, _| (i == 0).then_some(crate::aabb::Aabb::new(Vec3::NAN, Vec3::NAN)),
        calls: core::cell::Cell::new(0),
    }
}

/// `n` random boxes whose answers, after the first `n` calls, are NaN, infinite, inverted or
/// another box, drawn from `seed` and the call's number.
pub fn fickle_random(
    n: usize,
    seed: u64,
) -> Fickle<impl Fn(usize, u64) -> Option<crate::aabb::Aabb>> {
    let mut r = Lcg(seed);
    let boxes = (0..n)
        .map(|_| {
            let c = r.v(10.0);
            crate::aabb::Aabb::new(c, c + Vec3::splat(r.f() + 0.1))
        })
        .collect();
    Fickle {
        boxes,
        steady: n as u64,
        change: move |i, call| {
            let mut s = seed ^ (call << 20) ^ i as u64;
            let pick = (lcg(&mut s) * 5.0) as u32;
            let p = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 10.0;
            match pick {
                0 => Some(crate::aabb::Aabb::new(Vec3::NAN, Vec3::NAN)),
                1 => Some(crate::aabb::Aabb::new(p, Vec3::INFINITY)),
                2 => Some(crate::aabb::Aabb::new(p + Vec3::ONE, p)),
                3 => Some(crate::aabb::Aabb::new(p, p + Vec3::ONE)),
                _ => None,
            }
        },
        calls: core::cell::Cell::new(0),
    }
}

impl<T> AsMut<[T]> for Flip<T> {
    fn as_mut(&mut self) -> &mut [T] {
        &mut self.a
    }
}

/// A structure, the mesh it was built over and a ray, shared with the threads
/// [`Walks::end`] runs walks on: a walk that hangs fails the test instead of hanging the run.
pub struct Walks<A> {
    name: std::string::String,
    accel: std::sync::Arc<A>,
    pos: std::sync::Arc<Vec<Vec3>>,
    tris: std::sync::Arc<Vec<[u32; 3]>>,
    ray: Ray,
}

impl<A: Send + Sync + 'static> Walks<A> {
    /// `accel` over the mesh `(pos, tris)`, with `ray`; `name` labels the failures.
    pub fn new(name: &str, accel: A, pos: &[Vec3], tris: &[[u32; 3]], ray: Ray) -> Self {
        Self {
            name: name.into(),
            accel: std::sync::Arc::new(accel),
            pos: std::sync::Arc::new(pos.to_vec()),
            tris: std::sync::Arc::new(tris.to_vec()),
            ray,
        }
    }

    /// `walk(structure, mesh, ray)` on a thread of its own, which must return within ten
    /// seconds (the walks take microseconds); a hung walk's thread spins on until the test
    /// binary exits.
    pub fn end(&self, what: &str, walk: fn(&A, &TriangleMesh<'_>, &Ray)) {
        let (accel, pos, tris, ray) = (
            self.accel.clone(),
            self.pos.clone(),
            self.tris.clone(),
            self.ray,
        );
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            walk(&accel, &TriangleMesh::new(&pos, &tris), &ray);
            let _ = tx.send(());
        });
        if let Err(e) = rx.recv_timeout(std::time::Duration::from_secs(10)) {
            panic!("{}: {what} did not return within 10 s ({e})", self.name);
        }
    }
}
