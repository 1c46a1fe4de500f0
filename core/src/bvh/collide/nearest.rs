//! Minimum distance between two meshes, up to a bound: the same simultaneous descent as the
//! collision query, pruning node pairs whose box distance proves they cannot beat the best
//! pair so far.

use super::CollideError;
use super::body::{Body, DBox, Placement};
use super::distance::{DISTANCE_ERR_REL, triangle_distance};
use super::pairs::{PairStack, child_pairs, split_first};
use crate::bvh::BvhNode;
use crate::mesh::Primitive;
use crate::transform::Transform;
use glam::Vec3;

/// The closest triangle pair of two meshes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// Their distance ([`super::triangle_distance`]), in the first body's units; `0` when they
    /// intersect.
    pub distance: f64,
    /// Triangle of the first body.
    pub a: u32,
    /// Triangle of the second body.
    pub b: u32,
}

/// The pair of triangles (first body, second body placed by `b_to_a`) with the smallest
/// [`super::triangle_distance`], if that distance is at most `max_distance` (`+∞` for no
/// bound); `None` when every pair is farther. **Tie rule:** of pairs at the same computed
/// distance, the smallest `(a, b)` in lexicographic order, so the answer equals a
/// brute-force minimum over all pairs with that rule, whatever the trees.
///
/// Pruning is conservative with respect to rounding: a node pair is skipped only when
/// `box_distance·(1 − 2ε) − ε·M` exceeds the current best (or `max_distance`), with
/// `ε` = [`DISTANCE_ERR_REL`] and `M` the largest coordinate magnitude of both (placed)
/// meshes; by the error bound of [`super::triangle_distance`] no triangle pair in it can then
/// compute a distance at or below the best.
///
/// # Errors
///
/// [`CollideError::InvalidMaxDistance`] for a NaN or negative `max_distance` (nothing
/// traversed); [`CollideError::TreeTooDeep`], unreachable for built or loaded trees.
pub fn min_distance<NA, IA, NB, IB>(
    a: &Body<'_, NA, IA>,
    b: &Body<'_, NB, IB>,
    b_to_a: &Transform,
    max_distance: f64,
) -> Result<Option<Closest>, CollideError>
where
    NA: AsRef<[BvhNode]>,
    IA: AsRef<[u32]>,
    NB: AsRef<[BvhNode]>,
    IB: AsRef<[u32]>,
{
    if !(max_distance >= 0.0) {
        return Err(CollideError::InvalidMaxDistance);
    }
    let place = Placement::new(b_to_a);
    let (na, nb) = (a.nodes(), b.nodes());
    let (Some(ra), Some(rb)) = (na.first(), nb.first()) else {
        return Ok(None);
    };
    let Some(root_b) = place.place_box(&rb.bounds()) else {
        return Ok(None);
    };
    let root_a = DBox::from_aabb(&ra.bounds());
    let m = root_a.magnitude().max(root_b.magnitude());
    if !m.is_finite() {
        return Ok(None);
    }
    let lower = |d: f64| d * (1.0 - 2.0 * DISTANCE_ERR_REL) - DISTANCE_ERR_REL * m;
    let box_distance = |ia: u32, ib: u32| -> Option<f64> {
        let (x, y) = (na.get(ia as usize)?, nb.get(ib as usize)?);
        let yb = place.place_box(&y.bounds())?;
        Some(DBox::from_aabb(&x.bounds()).distance(&yb))
    };
    let mut best: Option<Closest> = None;
    let bound = |best: &Option<Closest>| best.map_or(max_distance, |c| c.distance);
    let mut stack = PairStack::new(0.0f64);
    let mut current = box_distance(0, 0).map(|d| (0u32, 0u32, d));
    while let Some((ia, ib, d)) = current {
        current = None;
        if lower(d) <= bound(&best)
            && let (Some(x), Some(y)) = (na.get(ia as usize), nb.get(ib as usize))
        {
            match split_first(x, y) {
                None => {
                    let placed = b.leaf_triangles(y).map(|(q, t)| (q, place.triangle(t)));
                    leaf_pairs(a.leaf_triangles(x), placed, &mut best, max_distance, &lower);
                }
                Some(first) => {
                    let node = if first { x } else { y };
                    let [c0, c1] = child_pairs(node, ia, ib, first);
                    let keep = |c: (u32, u32)| {
                        box_distance(c.0, c.1)
                            .filter(|&d| lower(d) <= bound(&best))
                            .map(|d| (c.0, c.1, d))
                    };
                    match (keep(c0), keep(c1)) {
                        (Some(p), Some(q)) => {
                            let (near, far) = if q.2 < p.2 { (q, p) } else { (p, q) };
                            stack.push(far)?;
                            current = Some(near);
                        }
                        (p, q) => current = p.or(q),
                    }
                }
            }
        }
        if current.is_none() {
            current = stack.pop();
        }
    }
    Ok(best)
}

/// Every pair of a triangle `(p, ta)` of one leaf and `(q, tb)` of the other (placed) against
/// the best so far (ties: smaller `(a, b)`).
fn leaf_pairs(
    leaf_a: impl Iterator<Item = (u32, [Vec3; 3])> + Clone,
    leaf_b: impl Iterator<Item = (u32, [Vec3; 3])>,
    best: &mut Option<Closest>,
    max_distance: f64,
    lower: &impl Fn(f64) -> f64,
) {
    for (q, tb) in leaf_b {
        let box_b = DBox::from_aabb(&Primitive::bounds(&tb));
        for (p, ta) in leaf_a.clone() {
            let bound = best.map_or(max_distance, |c| c.distance);
            if lower(DBox::from_aabb(&Primitive::bounds(&ta)).distance(&box_b)) > bound {
                continue;
            }
            let d = triangle_distance(&ta, &tb);
            let better = match best {
                None => d <= max_distance,
                Some(c) => d < c.distance || (d == c.distance && (p, q) < (c.a, c.b)),
            };
            if better {
                *best = Some(Closest {
                    distance: d,
                    a: p,
                    b: q,
                });
            }
        }
    }
}
