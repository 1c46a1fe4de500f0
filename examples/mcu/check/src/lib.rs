//! The checks `scripts/test-mcu.sh` runs on emulated microcontrollers and on the host, with
//! every result folded into one FNV-1a hash, so that "the same answers there" is one
//! comparison of two numbers.
//!
//! * **Ray queries** ([`ray_checks`]): a heightfield of `2·n²` triangles (heights from an
//!   integer hash, so the mesh is the same bits everywhere), a binary BVH built into the
//!   caller's storage, and four ray sets: a pinhole camera, random rays, rays aimed exactly at
//!   the midpoints of shared edges and at interior vertices. Each ray's closest hit (primitive,
//!   `t`, barycentric bits) and any-hit answer go into the hash. Edge and vertex rays come from
//!   above the surface and cross it, so a miss is a leak: they are counted, and must be zero.
//! * **Baked BVH** ([`baked_checks`]): a mesh and BVH baked on the host by `halfray bake`
//!   into `static` arrays (in flash on the target), loaded by `Bvh::from_parts` (which checks
//!   them), queried with four ray sets like the above.
//! * **Query image** ([`query_checks`]): the lean loop of the `mcu-query` image, random and
//!   aimed rays at a baked BVH, for the size and stack of the query path alone.
//! * **Half-edge** ([`halfedge_checks`]): a smaller heightfield built into fixed arenas, one
//!   Loop level (Warren weights), `validate()` on both, and the subdivided positions' bits into
//!   the hash.
//!
//! Everything is integer or IEEE-754 basic arithmetic (`+ − × ÷ √`, correctly rounded on every
//! target, in hardware or in software), so any difference in the hash is a difference in the
//! core's answers, not in a math library.
#![no_std]

mod query;
pub use query::{QUERY_STACK, any_in, closest_in, query_checks};

use halfray_core::Vec3;
use halfray_core::bvh::{BuildOptions, Bvh, BvhNode};
use halfray_core::halfedge::{
    EdgeRec, FaceRec, LoopWeights, SliceMesh, VertexRec, build_scratch_len,
};
use halfray_core::mesh::TriangleMesh;
use halfray_core::prelude::*;
use halfray_core::query::{Query, Triangles};
use halfray_core::ray::Ray;
use halfray_core::triangle::{TriangleHit, Watertight};

/// FNV-1a, 64-bit, over 32-bit words (little-endian bytes).
#[derive(Clone, Copy, Debug)]
pub struct Fnv(u64);

impl Fnv {
    /// The empty hash.
    pub const fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    /// Folds in one word.
    pub fn word(&mut self, w: u32) {
        for b in w.to_le_bytes() {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x100_0000_01b3);
        }
    }

    /// The hash so far.
    pub const fn value(&self) -> u64 {
        self.0
    }
}

impl Default for Fnv {
    fn default() -> Self {
        Self::new()
    }
}

/// Vertices of the `n × n`-quad heightfield.
pub const fn vertex_count(n: usize) -> usize {
    (n + 1) * (n + 1)
}

/// Triangles of the `n × n`-quad heightfield.
pub const fn triangle_count(n: usize) -> usize {
    2 * n * n
}

/// Height of grid vertex `(i, j)`: an integer hash mapped to `[0, 1/64)` exactly. With grid
/// steps of at least `2/32`, no face is steeper than 1 in 4, so rays that come down at more
/// than 70° from the horizontal cross the surface wherever they meet it (a miss is a leak).
fn height(i: usize, j: usize) -> f32 {
    let h = (i as u32).wrapping_mul(73_856_093) ^ (j as u32).wrapping_mul(19_349_663);
    (h.wrapping_mul(2_654_435_761) >> 22) as f32 / 65536.0
}

/// Fills `positions` and `triangles` with the heightfield over `[-1, 1]²` (`n` quads a side,
/// each split along a diagonal chosen by parity, counter-clockwise seen from `+z`).
fn heightfield(n: usize, positions: &mut [Vec3], triangles: &mut [[u32; 3]]) {
    let step = 2.0 / n as f32;
    for j in 0..=n {
        for i in 0..=n {
            positions[j * (n + 1) + i] =
                Vec3::new(i as f32 * step - 1.0, j as f32 * step - 1.0, height(i, j));
        }
    }
    let v = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
            let t = 2 * (j * n + i);
            if (i + j) % 2 == 0 {
                triangles[t] = [a, b, c];
                triangles[t + 1] = [a, c, d];
            } else {
                triangles[t] = [a, b, d];
                triangles[t + 1] = [b, c, d];
            }
        }
    }
}

/// A xorshift generator: the same stream on every target.
struct Rng(u32);

impl Rng {
    fn next(&mut self) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0
    }

    /// Uniform in `[0, 1)`, 24 bits, exact.
    fn unit(&mut self) -> f32 {
        (self.next() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Uniform in `[lo, hi)`.
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    /// A value in `0..n` (`0` for `n = 0`; no division by zero, so no panic path).
    fn below(&mut self, n: usize) -> usize {
        (self.next() as usize).checked_rem(n).unwrap_or(0)
    }

    /// A point `(±0.25, ±0.25, 1..2)` away from `target`: an origin above it.
    fn above(&mut self, target: Vec3) -> Vec3 {
        target
            + Vec3::new(
                self.range(-0.25, 0.25),
                self.range(-0.25, 0.25),
                self.range(1.0, 2.0),
            )
    }
}

/// The centres of the largest square grid of at most `rays` pixels, as `(u, v)` in
/// `(-½, ½)²`, row by row (`v` outer).
fn pixel_grid(rays: usize) -> impl Iterator<Item = (f32, f32)> {
    let side = (1..=rays).take_while(|s| s * s <= rays).last().unwrap_or(0);
    let at = move |i: usize| (i as f32 + 0.5) / side as f32 - 0.5;
    (0..side).flat_map(move |y| (0..side).map(move |x| (at(x), at(y))))
}

/// The caller's storage for [`ray_checks`] on an `n × n` heightfield: at least
/// [`vertex_count`], [`triangle_count`], `node_capacity(triangle_count)` and
/// [`triangle_count`] elements.
pub struct RayStorage<'a> {
    /// Vertex positions.
    pub positions: &'a mut [Vec3],
    /// Triangles.
    pub triangles: &'a mut [[u32; 3]],
    /// BVH nodes.
    pub nodes: &'a mut [BvhNode],
    /// BVH primitive indices.
    pub indices: &'a mut [u32],
}

/// Sizes of one machine's checks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Config {
    /// Quads per side of the ray-query heightfield.
    pub grid: usize,
    /// Rays per set (four sets; two queries per ray).
    pub rays_per_set: usize,
    /// Quads per side of the half-edge heightfield.
    pub halfedge_grid: usize,
}

/// The Cortex-M4F image (`mps2-an386`, 4 MiB RAM): 2 048 triangles, 4 096 rays.
pub const M4F: Config = Config {
    grid: 32,
    rays_per_set: 1024,
    halfedge_grid: 8,
};

/// The Cortex-M3 soft-float image (`lm3s6965evb`, 64 KiB RAM): 200 triangles, 1 024 rays.
pub const M3: Config = Config {
    grid: 10,
    rays_per_set: 256,
    halfedge_grid: 4,
};

/// What a run of checks did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// Queries made (closest and any hit count one each; half-edge checks count one).
    pub queries: u32,
    /// Closest hits found.
    pub hits: u32,
    /// Edge and vertex rays that missed or passed through the surface.
    pub leaks: u32,
}

impl Summary {
    /// Both summaries together.
    pub fn plus(self, o: Self) -> Self {
        Self {
            queries: self.queries + o.queries,
            hits: self.hits + o.hits,
            leaks: self.leaks + o.leaks,
        }
    }
}

/// Why a check could not run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CheckError {
    /// The storage is too small for the requested mesh.
    Storage,
    /// The BVH build failed.
    Build,
    /// The half-edge build, Loop subdivision, validation or export failed.
    Halfedge,
}

/// One ray's closest and any hit with the watertight test, folded into `hash` (primitive,
/// `t` and barycentric bits, or a miss marker; then the any-hit answer) and counted in
/// `summary`; returns the closest hit's `t`.
fn query_both<N: AsRef<[BvhNode]>, I: AsRef<[u32]>>(
    bvh: &Bvh<N, I>,
    mesh: &TriangleMesh<'_>,
    ray: &Ray,
    summary: &mut Summary,
    hash: &mut Fnv,
) -> Option<f32> {
    let closest = bvh.closest_hit(
        ray,
        &mut Triangles::new(mesh, &Watertight),
        &mut Query::new(),
    );
    let any = bvh.any_hit(
        ray,
        &mut Triangles::new(mesh, &Watertight),
        &mut Query::new(),
    );
    fold_answers(closest, any.is_some(), summary, hash);
    closest.map(|(_, hit)| hit.t)
}

/// Folds one ray's closest-hit answer (primitive, `t` and barycentric bits, or a miss) and
/// any-hit answer into `hash`, counting two queries and the hit in `summary`.
fn fold_answers(
    closest: Option<(u32, TriangleHit)>,
    any: bool,
    summary: &mut Summary,
    hash: &mut Fnv,
) {
    summary.queries += 2;
    match closest {
        Some((prim, hit)) => {
            summary.hits += 1;
            for w in [prim, hit.t.to_bits(), hit.b1.to_bits(), hit.b2.to_bits()] {
                hash.word(w);
            }
        }
        None => hash.word(u32::MAX),
    }
    hash.word(any as u32);
}

/// How far past its target (`t = 1`) an aimed ray's first hit may lie and not count as a leak
/// (ray parameter): the target is on the surface, but the direction `target − o` is rounded
/// to `f32`, so the line passes it, and crosses the surface, a few ulps of `t = 1` away
/// (`2⁻²³` each); `10⁻⁵` (84 of them) covers that with margin. A ray that slips through the
/// heightfield at its target has no other crossing near it: it misses, or meets the surface
/// again far beyond.
const AIMED_T_SLACK: f32 = 1.0e-5;

/// Builds the heightfield's BVH in `storage` and makes `rays_per_set` queries of each kind on
/// each of the four sets (see the crate docs), folding every answer into `hash`.
pub fn ray_checks(
    n: usize,
    rays_per_set: usize,
    storage: RayStorage<'_>,
    hash: &mut Fnv,
) -> Result<Summary, CheckError> {
    let (nv, nt) = (vertex_count(n), triangle_count(n));
    if storage.positions.len() < nv || storage.triangles.len() < nt {
        return Err(CheckError::Storage);
    }
    let positions = &mut storage.positions[..nv];
    let triangles = &mut storage.triangles[..nt];
    heightfield(n, positions, triangles);
    let mesh = TriangleMesh::new(positions, triangles);
    let bvh = Bvh::build(
        &mesh,
        storage.nodes,
        storage.indices,
        &BuildOptions::default(),
    )
    .map_err(|_| CheckError::Build)?;
    let mut summary = Summary::default();
    let mut rng = Rng(0x9e37_79b9);
    let mut query = |ray: &Ray, aimed: bool, summary: &mut Summary| {
        let t = query_both(&bvh, &mesh, ray, summary, hash);
        // Aimed rays reach their target at t = 1: a miss or a hit beyond it is a leak.
        summary.leaks += (aimed && t.is_none_or(|t| t > 1.0 + AIMED_T_SLACK)) as u32;
    };
    // Pinhole camera above the field.
    for (u, v) in pixel_grid(rays_per_set) {
        let ray = Ray::new(
            Vec3::new(0.0, -0.5, 2.5),
            Vec3::new(u * 1.6, v * 1.6 + 0.2, -1.0),
        );
        query(&ray, false, &mut summary);
    }
    // Random origins around the field, aimed at random points over it.
    for _ in 0..rays_per_set {
        let o = Vec3::new(
            rng.range(-3.0, 3.0),
            rng.range(-3.0, 3.0),
            rng.range(-1.0, 3.0),
        );
        let p = Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(0.0, 0.02),
        );
        query(&Ray::new(o, p - o), false, &mut summary);
    }
    // Aimed at the midpoint of an interior shared edge (a quad's diagonal or an interior grid
    // edge) from above: t = 1 at the target.
    for _ in 0..rays_per_set {
        let t = rng.below(nt);
        let [a, b, c] = triangles[t];
        let (p, q) = match rng.below(3) {
            0 => (a, b),
            1 => (b, c),
            _ => (c, a),
        };
        let (p, q) = (positions[p as usize], positions[q as usize]);
        let target = (p + q) * 0.5;
        let interior = target.x.abs() < 1.0 && target.y.abs() < 1.0;
        let o = rng.above(target);
        query(&Ray::new(o, target - o), interior, &mut summary);
    }
    // Aimed exactly at an interior vertex from above.
    for _ in 0..rays_per_set {
        let (i, j) = (1 + rng.below(n - 1), 1 + rng.below(n - 1));
        let target = positions[j * (n + 1) + i];
        let o = rng.above(target);
        query(&Ray::new(o, target - o), true, &mut summary);
    }
    Ok(summary)
}

/// Queries on a BVH baked on the host (`halfray bake`) and loaded with
/// [`Bvh::from_parts`] from `static` arrays: `rays_per_set` rays of each of four sets — a
/// pinhole camera framing the mesh, random rays through its box, rays aimed exactly at
/// vertices and at edge midpoints from outside the box — each with a closest- and an any-hit
/// query folded into `hash`. Fails with [`CheckError::Build`] when the baked data does not load.
pub fn baked_checks(
    nodes: &[BvhNode],
    indices: &[u32],
    mesh: &TriangleMesh<'_>,
    scratch: &mut [u32],
    rays_per_set: usize,
    hash: &mut Fnv,
) -> Result<Summary, CheckError> {
    let bvh = Bvh::from_parts(nodes, indices, mesh, scratch).map_err(|_| CheckError::Build)?;
    let b = bvh.bounds();
    let (lo, hi) = (b.min, b.max);
    let (center, size) = ((lo + hi) * 0.5, hi - lo);
    let reach = size.x.max(size.y).max(size.z);
    let mut summary = Summary::default();
    let mut rng = Rng(0x2545_f491);
    let mut query = |ray: &Ray, summary: &mut Summary| {
        query_both(&bvh, mesh, ray, summary, hash);
    };
    let eye = center + Vec3::new(0.3, -0.4, 1.0) * (1.5 * reach);
    for (u, v) in pixel_grid(rays_per_set) {
        let target = center + Vec3::new(u * reach, v * reach, 0.0);
        query(&Ray::new(eye, target - eye), &mut summary);
    }
    let outside = |rng: &mut Rng| {
        center
            + Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ) * (2.0 * reach)
    };
    for _ in 0..rays_per_set {
        let o = outside(&mut rng);
        let p = lo + size * Vec3::new(rng.unit(), rng.unit(), rng.unit());
        query(&Ray::new(o, p - o), &mut summary);
    }
    if mesh.positions.is_empty() || mesh.triangles.is_empty() {
        return Ok(summary);
    }
    for _ in 0..rays_per_set {
        let o = outside(&mut rng);
        let p = mesh.positions[rng.below(mesh.positions.len())];
        query(&Ray::new(o, p - o), &mut summary);
    }
    for _ in 0..rays_per_set {
        let o = outside(&mut rng);
        let Some(v) = mesh.triangle(rng.below(mesh.len())) else {
            continue;
        };
        let k = rng.below(3);
        let p = (v[k] + v[(k + 1) % 3]) * 0.5;
        query(&Ray::new(o, p - o), &mut summary);
    }
    Ok(summary)
}

/// The caller's arenas for [`halfedge_checks`] on an `n × n` heightfield: the mesh needs
/// [`vertex_count`]`(n)` vertices, `3n² + 2n` edges and [`triangle_count`]`(n)` faces; its Loop
/// level `V + E` vertices, `2E + 3F` edges and `4F` faces; `scratch` `6F` words.
pub struct HalfedgeStorage<'a> {
    /// Input vertex positions (`vertex_count(n)`).
    pub positions: &'a mut [Vec3],
    /// Input triangles (`triangle_count(n)`).
    pub triangles: &'a mut [[u32; 3]],
    /// The mesh's vertex, edge and face arenas.
    pub mesh: (&'a mut [VertexRec], &'a mut [EdgeRec], &'a mut [FaceRec]),
    /// The subdivided mesh's arenas.
    pub fine: (&'a mut [VertexRec], &'a mut [EdgeRec], &'a mut [FaceRec]),
    /// Build scratch.
    pub scratch: &'a mut [u32],
    /// Exported subdivided positions.
    pub out_positions: &'a mut [Vec3],
    /// Exported subdivided triangles.
    pub out_triangles: &'a mut [[u32; 3]],
}

/// Edges of the `n × n`-quad heightfield: `n(n+1)` in each grid direction and `n²` diagonals.
pub const fn edge_count(n: usize) -> usize {
    2 * n * (n + 1) + n * n
}

/// Builds the heightfield's half-edge mesh, subdivides it once (Loop, Warren weights),
/// validates both, and folds the subdivided positions and triangles into `hash`.
pub fn halfedge_checks(
    n: usize,
    s: HalfedgeStorage<'_>,
    hash: &mut Fnv,
) -> Result<Summary, CheckError> {
    let (nv, nt) = (vertex_count(n), triangle_count(n));
    if s.positions.len() < nv || s.triangles.len() < nt || s.scratch.len() < build_scratch_len(nt) {
        return Err(CheckError::Storage);
    }
    let positions = &mut s.positions[..nv];
    let triangles = &mut s.triangles[..nt];
    heightfield(n, positions, triangles);
    let mut coarse = SliceMesh::from_slices(s.mesh.0, s.mesh.1, s.mesh.2);
    coarse
        .build(positions, triangles, s.scratch)
        .map_err(|_| CheckError::Halfedge)?;
    coarse.validate().map_err(|_| CheckError::Halfedge)?;
    let mut fine = SliceMesh::from_slices(s.fine.0, s.fine.1, s.fine.2);
    coarse
        .subdivide_loop(&mut fine, LoopWeights::Warren)
        .map_err(|_| CheckError::Halfedge)?;
    fine.validate().map_err(|_| CheckError::Halfedge)?;
    let (np, nf) = fine
        .export(s.out_positions, s.out_triangles)
        .map_err(|_| CheckError::Halfedge)?;
    for p in &s.out_positions[..np] {
        for c in p.to_array() {
            hash.word(c.to_bits());
        }
    }
    for t in &s.out_triangles[..nf] {
        for &i in t {
            hash.word(i);
        }
    }
    Ok(Summary {
        queries: 1,
        hits: 0,
        leaks: 0,
    })
}
