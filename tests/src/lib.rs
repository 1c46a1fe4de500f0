//! Shared helpers for the cross-crate suites in `tests/tests/`.
//!
//! * [`Mesh`]: a tiny reader for the shared meshes (`v x y z` / `f a b c` lines, 1-based), with
//!   [`meshes_dir`] locating `../shared/meshes` (override with the `HALFRAY_MESHES` variable).
//! * [`min_angle_deg`]: the smallest angle of a triangle, to keep random triangles well shaped.
//! * [`Rng`]: SplitMix64, deterministic, no dependency.
//! * [`exact`]: error-free transformations (`two_sum`, `two_prod`) and an **exact** sign of
//!   `det[b − a, c − a, d]` for `f32` inputs, evaluated with floating-point expansions
//!   (Shewchuk 1997), so the test harness classifies rays without any rounding of its own.
//! * Exact edge and vertex rays: [`exact_edge_point`] (a representable point lying exactly on a
//!   mesh edge) and [`aim_exact`] (an `f32` ray whose exact line passes through a given `f32`
//!   point: `origin + 1·direction = target` holds exactly in real arithmetic);
//!   [`vertex_and_eighth_edge_points`], the exact solids' vertices and edge points.
//! * [`Target`] and [`classify`]: which triangles are incident to an aimed-at edge or vertex,
//!   and whether the exact ray crosses the surface there *robustly* (see [`classify`]).
//! * [`brute_triangles`]: the brute-force closest hit the acceleration-structure suites
//!   compare against, and [`par_map`] to spread their rays over the cores.
//!
//! ## Why the exact rays start where they start
//!
//! For a ray `o + t·d` with `f32` fields to pass *exactly* through an `f32` point `p`, each
//! component `p_i − o_i` must be (a power-of-two multiple of) an `f32`. When `p_i` has a full
//! 24-bit mantissa, that confines `|o_i|` to about `2·|p_i|`: a far camera cannot aim exactly at
//! a full-precision vertex. So the suites use two families, both exact:
//! * **far / camera-like origins** at targets with few significant bits — the exact solids
//!   (coordinates `0`, `±1`, dyadic edge points), also translated by `1e5` and `1e6` with the
//!   camera near the world origin;
//! * **local origins** (within the representable box around the target, about the model's own
//!   size) at targets with full mantissas — the vertices and representable edge points of
//!   `spot`, `torus` and `bunny`. Directions there have full mantissas.
//!
//! [`aim_exact`] snaps a wished-for origin onto the coarsest grid that makes the ray exact and
//! verifies exactness with error-free sums; it returns `None` when no such snap exists.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3, Vec3};
use halfray_core::Ray;
use halfray_core::mesh::TriangleMesh;
use halfray_core::query::{Query, RayQuery, TraversalStats, Triangles};
use halfray_core::triangle::{TriangleHit, TriangleIntersector, TriangleVariant};

/// Unit roundoff of `f32`, `2⁻²⁴`, as `f64`.
pub const U32: f64 = 1.0 / 16_777_216.0;

// ---------------------------------------------------------------------------------------------
// Brute force and parallel rays
// ---------------------------------------------------------------------------------------------

/// The oracle of the grid and kd-tree suites: `isect` prepared once for `ray` (`None` when it
/// refuses the ray), then every triangle of `mesh` in index order (indices out of range
/// skipped), keeping the smallest `t` in the ray's interval; strict `<`, so of equal `t` the
/// smaller index wins. Shares no code with the structures it checks.
pub fn brute_triangles<T: TriangleIntersector>(
    mesh: &TriangleMesh<'_>,
    isect: &T,
    ray: &Ray,
) -> Option<(u32, TriangleHit)> {
    let pre = isect.prepare(ray)?;
    let mut best: Option<(u32, TriangleHit)> = None;
    for i in 0..mesh.len() {
        let Some(v) = mesh.triangle(i) else { continue };
        if let Some(h) = isect.intersect_prepared(&pre, ray, &v)
            && best.is_none_or(|(_, b)| h.t < b.t)
        {
            best = Some((i as u32, h));
        }
    }
    best
}

/// The closest hit of `ray` in `accel` over the triangles of `mesh` tested by `isect`, with a
/// fresh context that adds to `stats` when given: the query call the suites make (the code
/// under test, not an oracle).
pub fn closest_by<'s, A: RayQuery + ?Sized, I: TriangleIntersector>(
    accel: &A,
    mesh: &TriangleMesh<'_>,
    isect: &I,
    ray: &Ray,
    stats: impl Into<Option<&'s mut TraversalStats>>,
) -> Option<(u32, TriangleHit)> {
    let mut ctx = Query::new().stats(stats);
    accel.closest_hit(ray, &mut Triangles::new(mesh, isect), &mut ctx)
}

/// The any hit of `ray` in `accel` over the triangles of `mesh` tested by `isect`
/// ([`closest_by`]'s counterpart, without statistics).
pub fn any_by<A: RayQuery + ?Sized, I: TriangleIntersector>(
    accel: &A,
    mesh: &TriangleMesh<'_>,
    isect: &I,
    ray: &Ray,
) -> Option<(u32, TriangleHit)> {
    accel.any_hit(ray, &mut Triangles::new(mesh, isect), &mut Query::new())
}

/// `f` over `items` on every core (`available_parallelism`, 2 if unknown): contiguous chunks
/// on scoped threads, results in the order of `items`. A panic in `f` propagates.
pub fn par_map<A: Sync, B: Send>(items: &[A], f: impl Fn(&A) -> B + Sync) -> Vec<B> {
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let chunk = items.len().div_ceil(threads).max(1);
    std::thread::scope(|s| {
        let handles: Vec<_> = items
            .chunks(chunk)
            .map(|c| s.spawn(|| c.iter().map(&f).collect::<Vec<B>>()))
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap())
            .collect()
    })
}

// ---------------------------------------------------------------------------------------------
// Meshes
// ---------------------------------------------------------------------------------------------

/// The shared mesh folder: `$HALFRAY_MESHES` if set, else `<workspace>/../shared/meshes`
/// (`CARGO_MANIFEST_DIR/../../shared/meshes`).
#[must_use]
pub fn meshes_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("HALFRAY_MESHES") {
        return PathBuf::from(dir);
    }
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/meshes")
}

/// An indexed triangle mesh: positions and 0-based triangles.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions (unreferenced ones included, as in the file).
    pub positions: Vec<Vec3>,
    /// Triangles, 0-based vertex indices.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// Loads `name` (e.g. `"cube.obj"`) from [`meshes_dir`]; panics with the path on error.
    #[must_use]
    pub fn load(name: &str) -> Self {
        let path = meshes_dir().join(name);
        Self::read(&path)
    }

    /// Reads an OBJ file of `v` and `f` lines; panics with the path on error.
    #[must_use]
    pub fn read(path: &Path) -> Self {
        let text = std::fs::read_to_string(path)
            .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
        Self::parse(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    /// Parses `v x y z` and `f a b c` lines (1-based, positive; other lines are ignored).
    /// Coordinates are parsed straight to `f32` (correctly rounded, like the core would).
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut m = Self::default();
        for (no, line) in text.lines().enumerate() {
            let mut it = line.split_whitespace();
            match it.next() {
                Some("v") => {
                    let c: Vec<f32> = it
                        .map(|x| x.parse::<f32>())
                        .collect::<Result<_, _>>()
                        .map_err(|e| format!("line {}: {e}", no + 1))?;
                    if c.len() != 3 {
                        return Err(format!("line {}: expected 3 coordinates", no + 1));
                    }
                    m.positions.push(Vec3::new(c[0], c[1], c[2]));
                }
                Some("f") => {
                    let c: Vec<u32> = it
                        .map(|x| x.parse::<u32>())
                        .collect::<Result<_, _>>()
                        .map_err(|e| format!("line {}: {e}", no + 1))?;
                    if c.len() != 3 || c.contains(&0) {
                        return Err(format!("line {}: expected 3 positive indices", no + 1));
                    }
                    m.triangles.push([c[0] - 1, c[1] - 1, c[2] - 1]);
                }
                _ => {}
            }
        }
        if let Some(bad) = m
            .triangles
            .iter()
            .flatten()
            .find(|&&i| i as usize >= m.positions.len())
        {
            return Err(format!("index {} out of range", bad + 1));
        }
        Ok(m)
    }

    /// The three corners of triangle `i`.
    #[inline]
    #[must_use]
    pub fn tri(&self, i: u32) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[i as usize];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// The mesh with every position mapped by `f` (topology unchanged, so shared vertices stay
    /// bit-identical).
    #[must_use]
    pub fn map(&self, f: impl Fn(Vec3) -> Vec3) -> Self {
        Self {
            positions: self.positions.iter().map(|&p| f(p)).collect(),
            triangles: self.triangles.clone(),
        }
    }

    /// The mesh translated by `t`, rounded to `f32` once per coordinate.
    #[must_use]
    pub fn translated(&self, t: Vec3) -> Self {
        self.map(|p| p + t)
    }

    /// Undirected edges `(lo, hi)` and the triangles using each, in first-use order.
    #[must_use]
    pub fn edge_faces(&self) -> Vec<((u32, u32), Vec<u32>)> {
        let mut index: HashMap<(u32, u32), usize> = HashMap::new();
        let mut out: Vec<((u32, u32), Vec<u32>)> = Vec::new();
        for (f, t) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                let slot = *index.entry(key).or_insert_with(|| {
                    out.push((key, Vec::new()));
                    out.len() - 1
                });
                out[slot].1.push(f as u32);
            }
        }
        out
    }

    /// For each vertex, the triangles using it.
    #[must_use]
    pub fn vertex_faces(&self) -> Vec<Vec<u32>> {
        let mut out = vec![Vec::new(); self.positions.len()];
        for (f, t) in self.triangles.iter().enumerate() {
            for &v in t {
                out[v as usize].push(f as u32);
            }
        }
        out
    }
}

/// The smallest interior angle of `tri`, in degrees, computed in `f64`.
#[must_use]
pub fn min_angle_deg(tri: &[Vec3; 3]) -> f64 {
    let p = tri.map(|x| x.as_dvec3());
    (0..3)
        .map(|i| {
            let u = p[(i + 1) % 3] - p[i];
            let v = p[(i + 2) % 3] - p[i];
            u.angle_between(v).to_degrees()
        })
        .fold(180.0, f64::min)
}

// ---------------------------------------------------------------------------------------------
// Deterministic random numbers
// ---------------------------------------------------------------------------------------------

/// The deterministic SplitMix64 generator shared with the frontend's ray sets.
pub use halfray::raysets::Rng;

// ---------------------------------------------------------------------------------------------
// Exact predicates
// ---------------------------------------------------------------------------------------------

/// Error-free transformations and exact signs on `f32` data.
pub mod exact {
    use glam::Vec3;

    /// Knuth's TwoSum: `a + b = s + e` exactly, `s = fl(a + b)`.
    #[inline]
    #[must_use]
    pub fn two_sum(a: f64, b: f64) -> (f64, f64) {
        let s = a + b;
        let bb = s - a;
        (s, (a - (s - bb)) + (b - bb))
    }

    /// TwoProduct with a fused multiply-add: `a·b = p + e` exactly (barring underflow).
    #[inline]
    #[must_use]
    pub fn two_prod(a: f64, b: f64) -> (f64, f64) {
        let p = a * b;
        (p, a.mul_add(b, -p))
    }

    /// `a − b` of two `f32` values, exactly, as an `f64` (panics if it would round — never for
    /// the coordinates in these suites, whose exponents differ by far less than 29).
    #[inline]
    #[must_use]
    pub fn diff(a: f32, b: f32) -> f64 {
        let (s, e) = two_sum(f64::from(a), -f64::from(b));
        assert!(e == 0.0, "inexact f64 difference {a} - {b}");
        s
    }

    /// A nonoverlapping floating-point expansion (Shewchuk 1997), small and on the stack.
    struct Expansion {
        c: [f64; 96],
        n: usize,
    }

    impl Expansion {
        fn new() -> Self {
            Self { c: [0.0; 96], n: 0 }
        }

        /// GROW-EXPANSION with zero elimination: adds `b` exactly.
        fn grow(&mut self, b: f64) {
            let mut q = b;
            let mut m = 0;
            for i in 0..self.n {
                let (s, e) = two_sum(q, self.c[i]);
                q = s;
                if e != 0.0 {
                    self.c[m] = e;
                    m += 1;
                }
            }
            if q != 0.0 {
                self.c[m] = q;
                m += 1;
            }
            self.n = m;
        }

        /// Adds `sign·x·y·z` exactly.
        fn add_triple(&mut self, sign: f64, x: f64, y: f64, z: f64) {
            let (p, e) = two_prod(x, y);
            let (p1, e1) = two_prod(p, z);
            let (p2, e2) = two_prod(e, z);
            for part in [p1, e1, p2, e2] {
                self.grow(sign * part);
            }
        }

        /// Adds `sign·det[x, y, z]` exactly.
        fn add_det(&mut self, sign: f64, x: [f64; 3], y: [f64; 3], z: [f64; 3]) {
            self.add_triple(sign, x[0], y[1], z[2]);
            self.add_triple(-sign, x[0], y[2], z[1]);
            self.add_triple(-sign, x[1], y[0], z[2]);
            self.add_triple(sign, x[1], y[2], z[0]);
            self.add_triple(sign, x[2], y[0], z[1]);
            self.add_triple(-sign, x[2], y[1], z[0]);
        }

        /// Sign of the exact sum: the sign of its largest component.
        fn sign(&self) -> i32 {
            match self.n {
                0 => 0,
                n if self.c[n - 1] > 0.0 => 1,
                _ => -1,
            }
        }
    }

    /// The exact sign of `det[x, y, z]` for `f64` vectors whose entries are exact.
    #[must_use]
    pub fn det3_sign(x: [f64; 3], y: [f64; 3], z: [f64; 3]) -> i32 {
        let mut e = Expansion::new();
        e.add_det(1.0, x, y, z);
        e.sign()
    }

    /// Exact sign of `det[b − a, c − a, d] = ((b − a) × (c − a))·d`: positive when the
    /// direction `d` leaves through the counter-clockwise side of triangle `abc` (it sees the
    /// back face), negative when it enters through it (front face), zero when `d` is parallel
    /// to the plane or the triangle is degenerate.
    ///
    /// Evaluated as `det[b, c, d] − det[a, c, d] − det[b, a, d]` (multilinearity), so only
    /// products of raw `f32` values enter the expansion: exact for every finite input whose
    /// triple products neither overflow nor underflow `f64`.
    #[must_use]
    pub fn orient_sign(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> i32 {
        let v = |p: Vec3| [f64::from(p.x), f64::from(p.y), f64::from(p.z)];
        let (a, b, c, d) = (v(a), v(b), v(c), v(d));
        let mut e = Expansion::new();
        e.add_det(1.0, b, c, d);
        e.add_det(-1.0, a, c, d);
        e.add_det(-1.0, b, a, d);
        e.sign()
    }

    /// The weight of the lowest set bit of `|x|` (`+∞` for zero): every multiple of it that
    /// fits in 24 bits, and nothing finer, can be added to `x` exactly.
    #[must_use]
    pub fn lowest_bit(x: f32) -> f64 {
        if x == 0.0 {
            return f64::INFINITY;
        }
        let bits = f64::from(x.abs()).to_bits();
        let exp = ((bits >> 52) & 0x7ff) as i32 - 1075;
        let mant = (bits & ((1u64 << 52) - 1)) | (1u64 << 52);
        2f64.powi(exp + mant.trailing_zeros() as i32)
    }

    /// `ulp(x)` of an `f32` (spacing of `f32` values at `|x|`), as `f64`.
    #[must_use]
    pub fn ulp(x: f32) -> f64 {
        let a = x.abs();
        f64::from(a.next_up()) - f64::from(a)
    }
}

// ---------------------------------------------------------------------------------------------
// Exact edge points and exact rays
// ---------------------------------------------------------------------------------------------

/// The point `a + (k/2^m)·(b − a)` when it is an `f32` lying **exactly** on the segment
/// (checked with error-free arithmetic), else `None`. `0 < k < 2^m`, `m ≤ 30`.
#[must_use]
pub fn exact_edge_point(a: Vec3, b: Vec3, k: u32, m: u32) -> Option<Vec3> {
    assert!(m <= 30 && k > 0 && k < (1 << m));
    let s = f64::from(k) / f64::from(1u32 << m);
    let mut p = Vec3::ZERO;
    for i in 0..3 {
        let (delta, err) = exact::two_sum(f64::from(b[i]), -f64::from(a[i]));
        if err != 0.0 {
            return None;
        }
        let (step, err) = exact::two_prod(s, delta);
        if err != 0.0 {
            return None;
        }
        let (sum, err) = exact::two_sum(f64::from(a[i]), step);
        if err != 0.0 {
            return None;
        }
        let q = sum as f32;
        if f64::from(q) != sum {
            return None;
        }
        p[i] = q;
    }
    (p != a && p != b).then_some(p)
}

/// The targets of the exact solids' vertex and edge rays: every vertex of `positions`, then on
/// each edge `a → b` of each triangle in turn the points `a + (s/8)·(b − a)`, `s = 1..=7`
/// (an edge shared by two triangles is listed twice, once each way). The points are computed
/// in `f32`: exact for the solids' coordinates in `{−1, 0, 1}`, not checked here.
#[must_use]
pub fn vertex_and_eighth_edge_points(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut targets = positions.to_vec();
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (positions[t[k] as usize], positions[t[(k + 1) % 3] as usize]);
            for s in 1..8 {
                targets.push(a + (b - a) * (s as f32 / 8.0));
            }
        }
    }
    targets
}

/// An `f32` ray whose exact line passes through `target` at `t = 1`: the origin is
/// `origin_guess` snapped, per component, to the coarsest grid needed so that
/// `direction = target − origin` is an `f32` computed without rounding. The identity
/// `origin + direction = target` is verified with error-free sums. `None` when the snap would
/// move the origin by more than `max_move` (absolute, per component) or no exact snap exists.
/// The interval is `(0, +∞]`.
#[must_use]
pub fn aim_exact(target: Vec3, origin_guess: Vec3, max_move: f64) -> Option<Ray> {
    let mut o = Vec3::ZERO;
    let mut d = Vec3::ZERO;
    for i in 0..3 {
        let p = target[i];
        let guess = origin_guess[i];
        let mut oi = guess;
        let mut di = p - oi;
        if !is_exact_diff(p, oi, di) {
            let g = exact::lowest_bit(p).max(exact::ulp(guess));
            let snapped = (f64::from(guess) / g).round() * g;
            if (snapped - f64::from(guess)).abs() > max_move {
                return None;
            }
            oi = snapped as f32;
            if f64::from(oi) != snapped {
                return None;
            }
            di = p - oi;
            if !is_exact_diff(p, oi, di) {
                return None;
            }
        }
        o[i] = oi;
        d[i] = di;
    }
    (d != Vec3::ZERO && d.is_finite()).then(|| Ray::new(o, d))
}

fn is_exact_diff(p: f32, o: f32, d: f32) -> bool {
    if !d.is_finite() {
        return false;
    }
    let (s, e) = exact::two_sum(f64::from(o), f64::from(d));
    e == 0.0 && s == f64::from(p)
}

// ---------------------------------------------------------------------------------------------
// Targets and robust transversality
// ---------------------------------------------------------------------------------------------

/// What a ray is aimed at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TargetKind {
    /// An interior point of an edge (both end vertices given).
    Edge(u32, u32),
    /// A vertex.
    Vertex(u32),
}

/// A point aimed at exactly, with the triangles incident to the edge or vertex it lies on.
#[derive(Clone, Debug)]
pub struct Target {
    /// Edge or vertex.
    pub kind: TargetKind,
    /// The exact `f32` point.
    pub point: Vec3,
    /// Triangles containing the edge or vertex (closed), the ones a leak is counted over.
    pub faces: Vec<u32>,
}

/// Clearance demanded around the aimed-at point, in units of `u·R` (`u = 2⁻²⁴`, `R` the largest
/// coordinate of `vertex − origin` over the incident vertices).
///
/// Why: an `f32` intersector does not see the exact ray. In the watertight test each sheared
/// vertex coordinate `a_kx − S_x·a_kz` carries at most about `4·u·R` of rounding (shear
/// quotient, product, difference; translation is exact for these rays), i.e. `4√2·u·R ≈ 5.7·u·R`
/// in the 2-D plane, and the other variants' errors are of the same order. If the exact
/// projection of the incident triangles along the ray covers a disc of radius `16·u·R` around
/// the target (about 3× that bound), every such perturbation of the projected vertices still
/// leaves the ray inside their union: the ray *must* hit one of them — any miss is a crack, not
/// an artefact of input rounding. Rays that do not qualify (silhouettes, grazing views, slivers)
/// are skipped and counted as skipped.
pub const CLEARANCE_IN_U: f64 = 16.0;

/// How a ray meets the surface at its target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// Common exact orientation sign of the incident triangles along the ray: `-1` = the ray
    /// enters through their counter-clockwise (outer) side, `+1` = it leaves.
    pub side: i32,
    /// Distance (in the projection along the ray) from the target to the nearest part of the
    /// incident triangles' boundary that does not contain the target.
    pub clearance: f64,
    /// The clearance required: `CLEARANCE_IN_U·u·R`.
    pub required: f64,
}

/// Projects points along `d` onto the coordinate plane perpendicular to `d`'s largest
/// component, relative to `o` (an oblique parallel projection, in `f64`).
#[derive(Clone, Copy, Debug)]
pub struct Projector {
    o: DVec3,
    k: [usize; 3],
    s: DVec2,
}

impl Projector {
    /// The projector of a ray.
    #[must_use]
    pub fn new(ray: &Ray) -> Self {
        let d = ray.direction.as_dvec3();
        let a = d.abs();
        let kz = a.max_position();
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        Self {
            o: ray.origin.as_dvec3(),
            k: [kx, ky, kz],
            s: DVec2::new(d[kx] / d[kz], d[ky] / d[kz]),
        }
    }

    /// The projection of `p`.
    #[must_use]
    pub fn project(&self, p: Vec3) -> DVec2 {
        let a = p.as_dvec3() - self.o;
        let [kx, ky, kz] = self.k;
        DVec2::new(a[kx] - self.s.x * a[kz], a[ky] - self.s.y * a[kz])
    }
}

/// Distance from `p` to the segment `[a, b]`, by cases: beyond either end it is the distance
/// to that end; in between, the height of the triangle `(a, b, p)` over `ab`.
fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    if (p - a).dot(ab) <= 0.0 {
        p.distance(a)
    } else if (p - b).dot(-ab) <= 0.0 {
        p.distance(b)
    } else {
        ab.perp_dot(p - a).abs() / ab.length()
    }
}

/// Decides whether the exact line of `ray` (which passes exactly through `target.point`)
/// crosses the surface there transversally and robustly:
/// 1. every incident triangle has the same non-zero **exact** orientation sign along the
///    direction ([`exact::orient_sign`]). For an edge of a consistently oriented mesh this is
///    exactly "the two opposite vertices lie strictly on opposite sides of the plane spanned by
///    the edge and the ray"; for a vertex it says the fan is seen as a proper star (all incident
///    faces front-facing, or all back-facing). Silhouette and grazing configurations — incident
///    faces on one side of the ray, or edge-on — fail this test;
/// 2. the projected incident triangles cover a disc of radius `CLEARANCE_IN_U·u·R` around the
///    target ([`CLEARANCE_IN_U`]).
///
/// Returns `None` when either fails (the ray is then skipped, not counted).
#[must_use]
pub fn classify(mesh: &Mesh, target: &Target, ray: &Ray) -> Option<Crossing> {
    let d = ray.direction;
    let mut side = 0;
    for &f in &target.faces {
        let [a, b, c] = mesh.tri(f);
        let s = exact::orient_sign(a, b, c, d);
        if s == 0 || (side != 0 && s != side) {
            return None;
        }
        side = s;
    }
    let proj = Projector::new(ray);
    let pt = proj.project(target.point);
    let mut r_max = (target.point.as_dvec3() - ray.origin.as_dvec3())
        .abs()
        .max_element();
    let mut clearance = f64::INFINITY;
    let on_target = |i: u32| match target.kind {
        TargetKind::Edge(a, b) => i == a || i == b,
        TargetKind::Vertex(v) => i == v,
    };
    for &f in &target.faces {
        let t = mesh.triangles[f as usize];
        for k in 0..3 {
            let (i, j) = (t[k], t[(k + 1) % 3]);
            let p = mesh.positions[i as usize];
            r_max = r_max.max((p.as_dvec3() - ray.origin.as_dvec3()).abs().max_element());
            // The boundary of the union near the target: for an edge target, the two other
            // edges of each triangle; for a vertex target, the edge opposite the vertex.
            let contains_target = match target.kind {
                TargetKind::Edge(..) => on_target(i) && on_target(j),
                TargetKind::Vertex(_) => on_target(i) || on_target(j),
            };
            if !contains_target {
                let q = mesh.positions[j as usize];
                clearance = clearance.min(segment_distance(pt, proj.project(p), proj.project(q)));
            }
        }
    }
    let required = CLEARANCE_IN_U * U32 * r_max;
    (clearance >= required).then_some(Crossing {
        side,
        clearance,
        required,
    })
}

/// The incident triangles that `variant` reports as hit by `ray`, as `(count, min t, max t)`.
#[must_use]
pub fn incident_hits(
    variant: TriangleVariant,
    mesh: &Mesh,
    faces: &[u32],
    ray: &Ray,
) -> (usize, f32, f32) {
    let mut n = 0;
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for &f in faces {
        if let Some(h) = variant.intersect(ray, &mesh.tri(f)) {
            n += 1;
            lo = lo.min(h.t);
            hi = hi.max(h.t);
        }
    }
    (n, lo, hi)
}

/// A random vertex target with its fan (`None` for a vertex no face uses).
#[must_use]
pub fn vertex_target(mesh: &Mesh, vertex_faces: &[Vec<u32>], v: u32) -> Option<Target> {
    let faces = vertex_faces[v as usize].clone();
    (!faces.is_empty()).then(|| Target {
        kind: TargetKind::Vertex(v),
        point: mesh.positions[v as usize],
        faces,
    })
}

/// An edge target at an exactly representable dyadic point `a + (k/2^m)(b − a)`, trying up to
/// `tries` random `(k, m)` with `m ≤ max_m` (`m = 1`, the midpoint, first).
pub fn edge_target(
    mesh: &Mesh,
    edge: (u32, u32),
    faces: &[u32],
    rng: &mut Rng,
    max_m: u32,
    tries: usize,
) -> Option<Target> {
    let a = mesh.positions[edge.0 as usize];
    let b = mesh.positions[edge.1 as usize];
    if a == b {
        return None;
    }
    for attempt in 0..tries {
        let m = if attempt == 0 {
            1
        } else {
            1 + rng.below(max_m as usize) as u32
        };
        let k = 1 + rng.below((1usize << m) - 1) as u32;
        if let Some(p) = exact_edge_point(a, b, k, m) {
            return Some(Target {
                kind: TargetKind::Edge(edge.0, edge.1),
                point: p,
                faces: faces.to_vec(),
            });
        }
    }
    None
}

/// Area-weighted normal of the incident triangles (`f64`, not normalised).
#[must_use]
pub fn fan_normal(mesh: &Mesh, faces: &[u32]) -> DVec3 {
    faces
        .iter()
        .map(|&f| {
            let [a, b, c] = mesh.tri(f).map(|p| p.as_dvec3());
            (b - a).cross(c - a)
        })
        .sum()
}

/// Leak counters for one variant over a ray set.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LeakCount {
    /// Edge rays tested.
    pub edge_rays: usize,
    /// Vertex rays tested.
    pub vertex_rays: usize,
    /// Edge rays with no incident hit.
    pub edge_leaks: usize,
    /// Vertex rays with no incident hit.
    pub vertex_leaks: usize,
    /// Rays where two or more incident triangles were hit.
    pub multi_hits: usize,
}

impl LeakCount {
    /// Records one ray.
    pub fn record(&mut self, edge: bool, hits: usize) {
        if edge {
            self.edge_rays += 1;
            self.edge_leaks += usize::from(hits == 0);
        } else {
            self.vertex_rays += 1;
            self.vertex_leaks += usize::from(hits == 0);
        }
        self.multi_hits += usize::from(hits >= 2);
    }

    /// Adds another count.
    pub fn add(&mut self, o: &Self) {
        self.edge_rays += o.edge_rays;
        self.vertex_rays += o.vertex_rays;
        self.edge_leaks += o.edge_leaks;
        self.vertex_leaks += o.vertex_leaks;
        self.multi_hits += o.multi_hits;
    }

    /// All rays.
    #[must_use]
    pub fn rays(&self) -> usize {
        self.edge_rays + self.vertex_rays
    }

    /// All leaks.
    #[must_use]
    pub fn leaks(&self) -> usize {
        self.edge_leaks + self.vertex_leaks
    }

    /// The stable, greppable report line.
    #[must_use]
    pub fn line(&self, variant: TriangleVariant, set: &str) -> String {
        format!(
            "LEAKS variant={} rays={} edge_leaks={} vertex_leaks={} edge_rays={} vertex_rays={} multi_hits={} set={}",
            variant.name(),
            self.rays(),
            self.edge_leaks,
            self.vertex_leaks,
            self.edge_rays,
            self.vertex_rays,
            self.multi_hits,
            set
        )
    }
}

/// The repository README's Rust examples, compiled and run as doctests by `cargo test`.
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
pub struct ReadmeDoctests;
