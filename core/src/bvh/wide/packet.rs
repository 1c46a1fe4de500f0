//! Packet traversal of a wide tree: the closest hits, or any hits, of up to [`PACKET`]
//! coherent rays walked down the tree together, one node test per node for the whole packet.
//!
//! A packet is the rays, of [`PACKET`] consecutive rays of a batch, whose directions lie in
//! the first ray's octant and within [`COHERENT_COS`] of its direction, whose origins lie
//! within [`COHERENT_ORIGIN`] of its origin ([`COHERENT_ORIGIN_ANY`] for any-hit rays), with
//! finite reciprocals and `t_min ≥ 0` (the common path of the single-ray node test) — when
//! they are at least three quarters of the chunk. The other rays are walked alone by the
//! single-ray query. The ray three quarters into the chunk is looked at first: when it is not
//! like the first, the whole chunk goes to the single-ray query before any per-ray work (an
//! incoherent order costs the batch nothing).
//! The packet's lanes are computed lane by lane over the chunk, in vector form, with the
//! operations of the single-ray setup (`Lanes::gather`).
//!
//! * **Inner nodes** are tested once for the packet with interval arithmetic: over the
//!   packet's ranges of padded origins and reciprocals, the smallest entry and the largest
//!   exit distance any of its rays can have, computed with the very roundings of the single-ray
//!   test ([`super::node_test`]) at the range ends. IEEE subtraction and multiplication are
//!   monotone in each operand, so each bound holds for every ray's own rounded distance: a
//!   child any ray of the packet would enter is entered by the packet.
//! * **Leaves** are tested ray by ray: each ray's own node test of the leaf's box (the same
//!   operations as the single-ray walk) picks the rays that test its triangles, with the
//!   single-ray leaf test (lane culls, then each triangle).
//!
//! Each ray's closest hit equals its single-ray answer bit for bit: a ray tests every leaf its
//! single walk would need to find its closest hit (its leaf-box test and every packet test
//! above it admit it), and the closest hit with the tie rule does not depend on the order
//! the leaves are tested in (module docs of [`crate::query`]). An any-hit ray tests every
//! leaf its box test admits until its first hit, so it finds one exactly when its single walk
//! does; which primitive depends on the order, and the packet's is not the ray's own. The
//! statistics count a packet's node tests once and each ray's triangle tests.
//!
//! Allocation-free: the packet's rays, answers and stack live in the call's frame
//! ([`STACK`] entries of 16 bytes).

use super::node::{ChildRef, LeafGroup, WideNode};
use super::node_test::{far_reciprocal, fold_slab, slab_axis};
use super::traverse::{
    RunLanes, STACK, entered_all, leaf_groups, leaf_hits, prefetch_child, sorted_keys,
};
use super::{WideBvh, add_stats};
use crate::query::walk::{PadFrame, cull_bound};
use crate::query::{LeafTest, TraversalStats};
use crate::ray::Ray;
use crate::simd;
use crate::simd::level::SimdLevel;

/// Rays per packet (at most 32: a packet's rays are the bits of a `u32`).
pub(super) const PACKET: usize = 16;

/// A ray joins its packet when the cosine of the angle between its direction and the first
/// ray's is at least this (about 2.5°): beyond, the interval bounds of the node test admit so
/// many nodes that single rays are faster. Only speed depends on it, never an answer.
pub(super) const COHERENT_COS: f32 = 0.999_05;

/// A ray joins its closest-hit packet when its origin lies within this share of the tree's
/// extent (half the longest side of its root box) of the first ray's, per axis (a
/// camera's rays share one origin): beyond, the packet's interval of origins admits nodes
/// none of its rays enters. Only speed depends on it, never an answer.
pub(super) const COHERENT_ORIGIN: f32 = 1.0 / 256.0;

/// [`COHERENT_ORIGIN`] of an any-hit packet: shadow rays towards one light leave a surface
/// from origins many pixels apart, yet their boxes are shared from the surface to the light;
/// a packet whose ray finds an occluder drops it. Only speed depends on it, never an answer.
pub(super) const COHERENT_ORIGIN_ANY: f32 = 1.0 / 16.0;

/// The likeness of a packet's rays to its first ray (module docs): only speed depends on it.
struct Coherence {
    origin: [f32; 3],
    direction: [f32; 3],
    /// `COHERENT_COS² · |direction|²`.
    cone: f32,
    /// The largest distance of an origin from the first ray's, per axis.
    reach: f32,
}

impl Coherence {
    /// The likeness to `first` with origins within `reach` of its origin, per axis.
    #[inline(always)]
    fn new(first: &Ray, reach: f32) -> Self {
        Self {
            origin: first.origin.to_array(),
            direction: first.direction.to_array(),
            cone: COHERENT_COS * COHERENT_COS * first.direction.length_squared(),
            reach,
        }
    }

    /// Whether a ray of origin `o` and direction `d` is like the first: its origin within
    /// reach and its direction within the cone (then in the first ray's octant unless a
    /// component is near zero). Written on plain `f32`s so that lane loops vectorise it.
    #[inline(always)]
    fn admits(&self, o: [f32; 3], d: [f32; 3]) -> bool {
        let (a, b) = (self.origin, self.direction);
        let far = |i: usize| (o[i] - a[i]).abs() <= self.reach;
        let dot = d[0] * b[0] + d[1] * b[1] + d[2] * b[2];
        let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        far(0) & far(1) & far(2) & (dot > 0.0) & (dot * dot >= self.cone * len2)
    }
}

/// The packet's rays side by side, lane `r` for ray `r`, as the node test wants them
/// ([`PaddedRay`](crate::bvh::padded_ray::PaddedRay)); lanes not in the packet have `t_min = +∞` and `bound = −∞`, which no box
/// test admits.
struct Lanes {
    origin_near: [[f32; PACKET]; 3],
    origin_far: [[f32; PACKET]; 3],
    inv: [[f32; PACKET]; 3],
    inv_far: [[f32; PACKET]; 3],
    t_min: [f32; PACKET],
    /// [`cull_bound`] of the ray's current `t_max`, capped at `f32::MAX` (the single-ray
    /// node test's interval end).
    bound: [f32; PACKET],
}

/// Per lane, all ones where a condition holds and zero where not: the form of a lane mask
/// that vector code selects with (`and`, `andnot`, `or`).
type LaneMask = [u32; PACKET];

/// All ones for `true`, zero for `false`.
#[inline(always)]
fn ones(c: bool) -> u32 {
    0u32.wrapping_sub(u32::from(c))
}

/// `a` where `on` is all ones, `b` where it is zero (bit by bit).
#[inline(always)]
fn select(on: u32, a: f32, b: f32) -> f32 {
    f32::from_bits(a.to_bits() & on | b.to_bits() & !on)
}

/// Bit `r` set where `m[r]` is set.
#[inline(always)]
fn lane_bits(m: &LaneMask) -> u32 {
    m.iter().enumerate().fold(0, |b, (r, &x)| b | (x & 1) << r)
}

/// The smallest (`MIN`) or largest value of `v` over the lanes of `on` (`±∞` for none),
/// folded in halves so that the lane loops vectorise.
// Lane loops are indexed: the form the compiler turns into vector instructions.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn masked_extreme<const MIN: bool>(v: &[f32; PACKET], on: &LaneMask) -> f32 {
    let none = if MIN {
        f32::INFINITY
    } else {
        f32::NEG_INFINITY
    };
    let pick = |a: f32, b: f32| if (a < b) == MIN { a } else { b };
    let mut x = [none; PACKET];
    for r in 0..PACKET {
        x[r] = select(on[r], v[r], none);
    }
    let mut half = PACKET / 2;
    while half > 0 {
        for r in 0..half {
            x[r] = pick(x[r], x[r + half]);
        }
        half /= 2;
    }
    x[0]
}

impl Lanes {
    /// Lanes to be written by [`Lanes::gather`].
    const ZERO: Self = Self {
        origin_near: [[0.0; PACKET]; 3],
        origin_far: [[0.0; PACKET]; 3],
        inv: [[0.0; PACKET]; 3],
        inv_far: [[0.0; PACKET]; 3],
        t_min: [0.0; PACKET],
        bound: [0.0; PACKET],
    };

    /// The lanes of `rays` (at most [`PACKET`]) in a tree of padding frame `frame` (origins
    /// relative to its centre, as the node boxes), computed lane by lane
    /// with the operations of [`SlabRay::new`](crate::aabb::SlabRay::new) and [`PaddedRay::new`](crate::bvh::padded_ray::PaddedRay::new) (so each lane's values
    /// are its ray's, bit for bit), and the mask of the rays that may join a packet of the
    /// octant `near`: valid ([`Ray::is_valid`]) with `t_min ≥ 0` and every reciprocal finite
    /// and normal (the common path of the single-ray node test), in the octant, and admitted
    /// by `coherence` (all ones in the lanes returned). Every lane is written; the lanes of the
    /// rays that do not join (and past the rays) get `t_min = +∞` and `bound = −∞`.
    // Lane loops are indexed: the form the compiler turns into vector instructions.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn gather(
        &mut self,
        rays: &[Ray],
        frame: &PadFrame,
        near: [usize; 3],
        coherence: &Coherence,
    ) -> LaneMask {
        let rays = rays.get(..PACKET).unwrap_or(rays);
        // Lanes past the rays hold a valid ray's values, and are masked out.
        let mut o = [[0.0f32; PACKET]; 3];
        let mut d = [[1.0f32; PACKET]; 3];
        let (mut t_min, mut t_max) = ([0.0f32; PACKET], [0.0f32; PACKET]);
        let mut ok: LaneMask = [0; PACKET];
        for (r, ray) in rays.iter().enumerate() {
            let r = r & (PACKET - 1);
            let (p, v) = (ray.origin.to_array(), ray.direction.to_array());
            for axis in 0..3 {
                o[axis][r] = p[axis];
                d[axis][r] = v[axis];
            }
            (t_min[r], t_max[r]) = (ray.t_min, ray.t_max);
            ok[r] = u32::MAX;
        }
        for r in 0..PACKET {
            let at = |v: &[[f32; PACKET]; 3]| [v[0][r], v[1][r], v[2][r]];
            ok[r] &= ones(coherence.admits(at(&o), at(&d)));
        }
        // `Ray::is_valid`, and the packet's conditions, lane by lane.
        const EXP: u32 = 0x7F80_0000;
        let out = self;
        for axis in 0..3 {
            let n = near[axis] == 1;
            for r in 0..PACKET {
                let (oa, da) = (o[axis][r], d[axis][r]);
                let inv = 1.0 / da;
                let normal = (inv.abs() >= f32::MIN_POSITIVE) & (inv.abs() < f32::INFINITY);
                ok[r] &= ones(
                    (oa.to_bits() & EXP != EXP)
                        & (da.to_bits() & EXP != EXP)
                        & normal
                        & (da.is_sign_negative() == n),
                );
                out.inv[axis][r] = inv;
                out.inv_far[axis][r] = far_reciprocal(inv);
            }
        }
        for r in 0..PACKET {
            ok[r] &= ones((t_min[r] >= 0.0) & (t_min[r] < f32::INFINITY) & (t_min[r] <= t_max[r]));
        }
        for r in 0..PACKET {
            // In the frame of the node boxes, as the single-ray walk (`PadFrame::local`).
            let (local, pad) = frame.local(glam::Vec3::new(o[0][r], o[1][r], o[2][r]));
            for axis in 0..3 {
                let toward = pad.copysign(d[axis][r]);
                out.origin_near[axis][r] = local[axis] + toward;
                out.origin_far[axis][r] = local[axis] - toward;
            }
            let bound = cull_bound(t_max[r]).min(f32::MAX);
            out.t_min[r] = select(ok[r], t_min[r], f32::INFINITY);
            out.bound[r] = select(ok[r], bound, f32::NEG_INFINITY);
        }
        ok
    }

    /// The rays of `bits` that enter slot `slot` of `node` within their own intervals: the
    /// single-ray node test of that box ([`PaddedRay::hit_children`](crate::bvh::padded_ray::PaddedRay::hit_children)), ray by ray, `near` the
    /// packet's near corners.
    // Lane loops are indexed: the form the compiler turns into vector instructions.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn entering<const W: usize>(&self, node: &WideNode<W>, slot: usize, near: [usize; 3]) -> u32 {
        let slot = slot & (W - 1);
        let mut t_enter = self.t_min;
        let mut t_exit = self.bound;
        for axis in 0..3 {
            let n = near[axis] & 1;
            let lo = node.bounds[n][axis][slot];
            let hi = node.bounds[1 - n][axis][slot];
            let (on, of) = (&self.origin_near[axis], &self.origin_far[axis]);
            let (inv, inv_far) = (&self.inv[axis], &self.inv_far[axis]);
            for r in 0..PACKET {
                (t_enter[r], t_exit[r]) = slab_axis(
                    (lo, hi),
                    (on[r], of[r]),
                    (inv[r], inv_far[r]),
                    (t_enter[r], t_exit[r]),
                );
            }
        }
        simd::mask_le(&t_enter, &t_exit)
    }

    /// The largest interval end of the packet (`−∞` when no ray is left).
    #[inline(always)]
    fn max_bound(&self) -> f32 {
        self.bound.iter().fold(f32::NEG_INFINITY, |m, &b| m.max(b))
    }
}

/// The packet's rays as one: per axis, the ends of the ranges of its padded origins and
/// reciprocals that give the smallest entry and the largest exit distance.
struct Interval {
    /// The near corner per axis (the octant's).
    near: [usize; 3],
    /// Per axis, the origin giving the smallest entry: the largest near origin for a
    /// positive direction (the entry falls with the origin), the smallest for a negative one.
    origin_near: [f32; 3],
    /// Per axis, the origin giving the largest exit.
    origin_far: [f32; 3],
    /// Per axis, the smallest and largest reciprocal.
    inv: [[f32; 2]; 3],
    /// Per axis, the smallest and largest far reciprocal.
    inv_far: [[f32; 2]; 3],
    /// The smallest `t_min`.
    t_min: f32,
}

impl Interval {
    /// The interval of the rays of `lanes` where `packet` holds (at least one), all with directions of the
    /// octant `near`.
    #[inline(always)]
    fn new(lanes: &Lanes, packet: &LaneMask, near: [usize; 3]) -> Self {
        let lo = |v: &[f32; PACKET]| masked_extreme::<true>(v, packet);
        let hi = |v: &[f32; PACKET]| masked_extreme::<false>(v, packet);
        let mut out = Self {
            near,
            origin_near: [0.0; 3],
            origin_far: [0.0; 3],
            inv: [[0.0; 2]; 3],
            inv_far: [[0.0; 2]; 3],
            t_min: lo(&lanes.t_min),
        };
        for (axis, &n) in near.iter().enumerate() {
            // `n` is 1 for a negative direction: the distances then fall as the difference
            // `plane − origin` grows.
            let (on, of) = (&lanes.origin_near[axis], &lanes.origin_far[axis]);
            (out.origin_near[axis], out.origin_far[axis]) = if n == 1 {
                (lo(on), hi(of))
            } else {
                (hi(on), lo(of))
            };
            out.inv[axis] = [lo(&lanes.inv[axis]), hi(&lanes.inv[axis])];
            out.inv_far[axis] = [lo(&lanes.inv_far[axis]), hi(&lanes.inv_far[axis])];
        }
        out
    }

    /// Entry-distance bounds of every child of `node` and the mask of the children some ray
    /// of the packet may enter over `[t_min, bound]` (see the module docs): each entry bound
    /// is at most every ray's entry distance, each exit bound at least every ray's exit.
    // Lane loops are indexed: the form the compiler turns into vector instructions.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn hit_children<const W: usize>(&self, node: &WideNode<W>, bound: f32) -> ([f32; W], u32) {
        let mut t_enter = [self.t_min; W];
        let mut t_exit = [bound; W];
        for axis in 0..3 {
            let n = self.near[axis] & 1;
            let lo = &node.bounds[n][axis];
            let hi = &node.bounds[1 - n][axis];
            let (on, of) = (self.origin_near[axis], self.origin_far[axis]);
            let [i0, i1] = self.inv[axis];
            let [f0, f1] = self.inv_far[axis];
            for i in 0..W {
                // The difference is at its extreme for the chosen origin; the product of a
                // fixed difference is monotone in the reciprocal, so its extremes are at the
                // range's ends. Finite reciprocals and finite or infinite bounds: no NaN.
                let d = lo[i] - on;
                let (a, b) = (d * i0, d * i1);
                let t_near = if a < b { a } else { b };
                let e = hi[i] - of;
                let (a, b) = (e * f0, e * f1);
                let t_far = if a > b { a } else { b };
                (t_enter[i], t_exit[i]) = fold_slab(t_near, t_far, (t_enter[i], t_exit[i]));
            }
        }
        (t_enter, simd::mask_le(&t_enter, &t_exit))
    }
}

/// The most chunks of [`PACKET`] rays a batch leaves to single rays in a row while its
/// packets do not share their leaves ([`Sharing`]), before it tries a packet again (1 024
/// rays): at most one chunk in 65 pays for a packet that does not pay. Only speed depends on
/// it.
pub(super) const MAX_WAIT: u32 = 64;

/// The bound of [`Sharing`]'s running sum of the packets' surpluses: a few packets' worth, so
/// that the sum follows the rays' spacing as it changes along a batch. Only speed depends on
/// it.
pub(super) const SHARE_WINDOW: i32 = 64;

/// Whether a batch's next chunk is walked as a packet: the surpluses of rays over leaves of
/// its recent packets ([`WideBvh::packet_hits`]) summed within `±SHARE_WINDOW`; while
/// the sum is below zero, the chunks after a packet go to single rays, 1, then 2, 4, … up to
/// [`MAX_WAIT`] of them at each packet that keeps it below zero. Only speed depends on it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Sharing {
    share: i32,
    wait: u32,
    next_wait: u32,
}

impl Sharing {
    /// No packet walked yet.
    pub(super) const NEW: Self = Self {
        share: 0,
        wait: 0,
        next_wait: 1,
    };

    /// `true` when the next chunk is tried as a packet; `false` (one chunk of the wait
    /// counted) when it goes to single rays.
    #[inline(always)]
    pub(super) fn try_packet(&mut self) -> bool {
        let go = self.wait == 0;
        self.wait = self.wait.saturating_sub(1);
        go
    }

    /// Counts a packet's `surplus` (as [`WideBvh::packet_hits`] returns it).
    #[inline(always)]
    pub(super) fn record(&mut self, surplus: i32) {
        self.share = self
            .share
            .saturating_add(surplus)
            .clamp(-SHARE_WINDOW, SHARE_WINDOW);
        if self.share >= 0 {
            self.next_wait = 1;
        } else {
            self.wait = self.next_wait;
            self.next_wait = (self.next_wait * 2).min(MAX_WAIT);
        }
    }
}

/// A stacked child: its reference, its parent node and slot (for a leaf's box) and the
/// packet's entry bound.
#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    parent: u32,
    slot: u32,
    t_enter: f32,
}

impl Entry {
    const ROOT: Self = Self {
        child: 0,
        parent: 0,
        slot: 0,
        t_enter: 0.0,
    };
}

/// The packet walk's stack ([`STACK`] entries), made once per batch and reused from packet to
/// packet.
pub(super) struct PacketStack([Entry; STACK]);

impl PacketStack {
    /// An empty stack (its entries are written before they are read).
    #[inline(always)]
    pub(super) fn new() -> Self {
        Self([Entry::ROOT; STACK])
    }
}

impl<const W: usize, N, T> WideBvh<W, N, T>
where
    N: AsRef<[WideNode<W>]>,
    T: AsRef<[LeafGroup]>,
{
    /// Walks the coherent rays of `rays` (at most [`PACKET`]) as one packet, passing each
    /// one's closest hit (with `ANY`, an any hit: the first primitive its leaf test reports in
    /// its interval, in the packet's order; a ray that has one leaves the packet) to
    /// `found(index, answer)`; returns the rays left to the single-ray
    /// walk (bit `i` for `rays[i]`; invalid rays among them) and how well the packet shared
    /// its leaves: the rays that entered the leaves it reached, summed, less the number of
    /// those leaves, when they are more than one for two rays; else 1 (such a packet costs
    /// little and shares its node tests: rays that mostly pass between small objects, as over
    /// the corpus's scatter mesh), and 0 when no packet was walked. Below zero, fewer than one
    /// ray a leaf: its rays are too far apart for the tree's leaves (fine triangles, rays many
    /// pixels apart), each leaf's box test serves less than one ray, the packet's order is no
    /// ray's own, and single rays are faster. `stack` is the walk's, reused from packet to
    /// packet.
    #[inline(always)]
    pub(super) fn packet_hits<LT: LeafTest, L: SimdLevel, const ANY: bool>(
        &self,
        level: L,
        rays: &[Ray],
        leaf: &mut LT,
        (PacketStack(stack), stats): (&mut PacketStack, Option<&mut TraversalStats>),
        mut found: impl FnMut(usize, Option<(u32, LT::Hit)>),
    ) -> (u32, i32) {
        let rays = rays.get(..PACKET).unwrap_or(rays);
        let (nodes, groups) = (self.nodes(), self.groups());
        let Some(reference) = rays.first() else {
            return (0, 0);
        };
        // The packet is the rays like the first one (module docs); the others walk alone.
        let d0 = reference.direction;
        let near = [d0.x, d0.y, d0.z].map(|c| usize::from(c.is_sign_negative()));
        // The tree's size, wherever it lies: half its root box's longest side.
        let side = self.root_box.extent().max_element();
        let half = if side > 0.0 && side.is_finite() {
            0.5 * side
        } else {
            0.0
        };
        let share = if ANY {
            COHERENT_ORIGIN_ANY
        } else {
            COHERENT_ORIGIN
        };
        let coherence = Coherence::new(reference, share * half);
        let alike = |ray: &Ray| coherence.admits(ray.origin.to_array(), ray.direction.to_array());
        let all = u32::MAX >> (32 - rays.len() as u32);
        // One ray first, the one three quarters in: rays in an order that is not coherent (a
        // stride, random rays) leave at once, before any per-ray setup; of rays fanning out
        // from the first (a scanline), fewer than three quarters would join when it does not.
        let probe = (rays.len() * 3).div_ceil(4).saturating_sub(1);
        // A tree whose root is a leaf (no node) has nothing to share: every ray goes alone.
        if nodes.is_empty() || rays.len() < 2 || !rays.get(probe).is_some_and(alike) {
            return (all, 0);
        }
        let mut lanes = Lanes::ZERO;
        let joined = lanes.gather(rays, &self.pad_frame, near, &coherence);
        let packet = lane_bits(&joined);
        if packet.count_ones() * 4 < rays.len() as u32 * 3 || packet.count_ones() < 2 {
            // Too few alike: a packet would walk nodes for few rays.
            return (all, 0);
        }
        let interval = Interval::new(&lanes, &joined, near);

        // Per ray: its `t_max` as the walk shrinks it, its best hit so far and its leaf test's
        // setup (made at its first leaf; `Some(None)`: refused, it hits nothing).
        let mut t_max: [f32; PACKET] =
            core::array::from_fn(|r| rays.get(r).map_or(0.0, |x| x.t_max));
        let mut best: [Option<(u32, LT::Hit)>; PACKET] = core::array::from_fn(|_| None);
        let mut prepared: [Option<Option<LT::Prepared>>; PACKET] = core::array::from_fn(|_| None);
        let mut local = TraversalStats::default();
        // Leaves the packet reached, and rays that entered them, summed.
        let (mut leaves, mut entered) = (0i32, 0i32);
        let mut sp = 0usize;
        let mut next = Entry::ROOT;
        let mut bound = lanes.max_bound();
        'walk: loop {
            match ChildRef::decode(next.child) {
                ChildRef::Inner(index) => {
                    if let Some(node) = nodes.get(index as usize) {
                        local.nodes_visited += 1;
                        let (dist, mut mask) = interval.hit_children(node, bound);
                        if entered_all(&local, nodes) {
                            // No tree (`entered_all`): the walk enters no further node.
                            mask = 0;
                        }
                        let entry = |slot: usize| Entry {
                            child: node.child[slot & (W - 1)],
                            parent: index,
                            slot: slot as u32,
                            t_enter: dist[slot & (W - 1)],
                        };
                        if mask != 0 && mask & (mask - 1) == 0 {
                            next = entry(mask.trailing_zeros() as usize);
                            continue 'walk;
                        }
                        if mask != 0 {
                            let keys = sorted_keys(level, &dist, mask);
                            let count = mask.count_ones() as usize;
                            // Nearest first; any-hit rays farthest first (see
                            // `WideBvh::push_hits_any`: rays leaving a surface).
                            let (visit, rest) = if ANY {
                                (count - 1, keys.get(..count - 1).unwrap_or(&[]))
                            } else {
                                (0, keys.get(1..count).unwrap_or(&[]))
                            };
                            // The one visited after `next` is pushed last.
                            let n = rest.len();
                            for j in 0..n {
                                let Some(&k) = rest.get(if ANY { j } else { n - 1 - j }) else {
                                    break;
                                };
                                let e = entry((k & 7) as usize);
                                if let Some(s) = stack.get_mut(sp) {
                                    *s = e;
                                    sp += 1;
                                }
                                prefetch_child(nodes, groups, e.child);
                            }
                            next = entry((keys[visit & (W - 1)] & 7) as usize);
                            continue 'walk;
                        }
                    }
                }
                ChildRef::Leaf { start, count } => {
                    if let Some(parent) = nodes.get(next.parent as usize) {
                        let mut todo = lanes.entering(parent, next.slot as usize, near) & packet;
                        leaves += 1;
                        entered += todo.count_ones() as i32;
                        while todo != 0 {
                            let r = todo.trailing_zeros() as usize;
                            todo &= todo - 1;
                            let (Some(ray), Some(pre), Some(best), Some(t_max)) = (
                                rays.get(r),
                                prepared.get_mut(r),
                                best.get_mut(r),
                                t_max.get_mut(r),
                            ) else {
                                break;
                            };
                            let Some(pre) = pre.get_or_insert_with(|| leaf.prepare_valid(ray))
                            else {
                                // Refused by the leaf test: no hit, as for the single-ray walk.
                                lanes.t_min[r] = f32::INFINITY;
                                lanes.bound[r] = f32::NEG_INFINITY;
                                continue;
                            };
                            local.primitives_tested += u64::from(count);
                            let mut cur = Ray {
                                t_max: *t_max,
                                ..*ray
                            };
                            if leaf_hits::<_, _, ANY>(
                                level,
                                leaf,
                                pre,
                                (
                                    leaf_groups(groups, start, count),
                                    RunLanes::new(start, count),
                                    true,
                                ),
                                (&mut cur, best),
                            ) {
                                if ANY {
                                    // Answered: no box admits the ray any more.
                                    lanes.t_min[r] = f32::INFINITY;
                                    lanes.bound[r] = f32::NEG_INFINITY;
                                } else {
                                    *t_max = cur.t_max;
                                    lanes.bound[r] = cull_bound(cur.t_max).min(f32::MAX);
                                }
                            }
                        }
                        bound = lanes.max_bound();
                        if ANY && bound == f32::NEG_INFINITY {
                            // Every ray answered or refused.
                            break 'walk;
                        }
                    }
                }
                ChildRef::Empty => {}
            }
            // The next entry some ray may still need.
            loop {
                let Some(top) = sp.checked_sub(1) else {
                    break 'walk;
                };
                sp = top;
                if let Some(e) = stack.get(sp)
                    && e.t_enter <= bound
                {
                    next = *e;
                    break;
                }
            }
        }
        add_stats(stats, &local);
        for (i, best) in best.iter_mut().enumerate() {
            if packet >> i & 1 == 1 {
                found(i, best.take());
            }
        }
        // Up to one leaf for two rays, a packet costs little whatever it shares: it counts
        // as a packet that paid, so that one packet of many unshared leaves does not keep
        // the batch's share below zero (and its chunks alone) for the rest of the batch.
        let many = leaves > PACKET as i32 / 2;
        (all & !packet, if many { entered - leaves } else { 1 })
    }
}

#[cfg(test)]
mod tests;
