//! An oracle for edge collapses that shares nothing with the half-edge code: the rules of
//! `Mesh::can_collapse_edge` (its documented list) evaluated from the exported triangle list
//! and positions alone (neighbour sets, face counts per edge, exact rational normals), and
//! the triangle list a collapse must leave behind.

use glam::Vec3;
use num_rational::BigRational;
use num_traits::ToPrimitive;
use std::collections::{BTreeMap, BTreeSet};

/// A triangle list as exported: positions by vertex id, triangles as vertex ids.
pub struct Faces<'a> {
    /// Positions, indexed by vertex id.
    pub positions: &'a [Vec3],
    /// Live triangles, counter-clockwise.
    pub triangles: &'a [[u32; 3]],
}

impl Faces<'_> {
    /// Faces per undirected edge.
    fn edge_counts(&self) -> BTreeMap<(u32, u32), usize> {
        let mut m = BTreeMap::new();
        for t in self.triangles {
            for i in 0..3 {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                *m.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        m
    }

    /// Distinct neighbours of `v`.
    fn neighbours(&self, v: u32) -> BTreeSet<u32> {
        let mut s = BTreeSet::new();
        for t in self.triangles.iter().filter(|t| t.contains(&v)) {
            s.extend(t.iter().copied().filter(|&w| w != v));
        }
        s
    }

    /// Whether `collapse_edge` must accept collapsing the edge `v0 → v1` with the survivor at
    /// `target`: rules 2–7 of `can_collapse_edge` (wings distinct, no ear, an interior edge
    /// does not join two boundaries, the link condition, no interior wing of valence 3, no
    /// fold-over by the exact sign of old·new normal). `None` when the answer rests on a
    /// fold-over sign within [`FOLD_ABSTAIN_REL`] of zero, where the documented `f64`
    /// evaluation may decide either way. `target` must be finite.
    pub fn may_collapse(&self, v0: u32, v1: u32, target: Vec3) -> Option<bool> {
        let counts = self.edge_counts();
        let key = |a: u32, b: u32| (a.min(b), a.max(b));
        let boundary_edge = |a: u32, b: u32| counts.get(&key(a, b)) == Some(&1);
        let on_boundary = |v: u32| {
            counts
                .iter()
                .any(|(&(a, b), &n)| n == 1 && (a == v || b == v))
        };
        let wings: Vec<&[u32; 3]> = self
            .triangles
            .iter()
            .filter(|t| t.contains(&v0) && t.contains(&v1))
            .collect();
        let opposite: Vec<u32> = wings
            .iter()
            .map(|t| *t.iter().find(|&&w| w != v0 && w != v1).unwrap_or(&v0))
            .collect();
        // 2. Wings coincide.
        if opposite.len() == 2 && opposite[0] == opposite[1] {
            return Some(false);
        }
        // 3. Ear: a wing face whose two other edges are on the boundary.
        if opposite
            .iter()
            .any(|&w| boundary_edge(v0, w) && boundary_edge(v1, w))
        {
            return Some(false);
        }
        // 4. An interior edge joining two boundary vertices.
        if wings.len() == 2 && on_boundary(v0) && on_boundary(v1) {
            return Some(false);
        }
        // 5. Link condition.
        let (n0, n1) = (self.neighbours(v0), self.neighbours(v1));
        if n0.intersection(&n1).any(|w| !opposite.contains(w)) {
            return Some(false);
        }
        // 6. An interior wing vertex of valence 3.
        if opposite
            .iter()
            .any(|&w| !on_boundary(w) && self.neighbours(w).len() == 3)
        {
            return Some(false);
        }
        // 7. Fold-over, exactly: every other face around v0 or v1 keeps old·new > 0 (faces
        // already degenerate are skipped).
        let at = |v: u32| self.positions[v as usize];
        let mut certain = true;
        for t in self.triangles {
            let touches = t.contains(&v0) || t.contains(&v1);
            if !touches || (t.contains(&v0) && t.contains(&v1)) {
                continue;
            }
            let old_p = t.map(at);
            let new_p = t.map(|v| if v == v0 || v == v1 { target } else { at(v) });
            let (old, new) = (normal(old_p), normal(new_p));
            let zero = BigRational::default();
            let dot: BigRational = (0..3).map(|i| &old[i] * &new[i]).sum();
            // The scale of the f64 evaluation's rounding: |b − a|·|c − a| of both faces.
            let band = FOLD_ABSTAIN_REL * edge_scale(old_p) * edge_scale(new_p);
            let near_zero = dot.to_f64().is_none_or(|x| x.abs() <= band);
            if old.iter().all(|c| *c == zero) {
                // Degenerate: skipped by the rule; a tiny rounded normal may not be.
                certain &= !near_zero;
                continue;
            }
            if near_zero {
                certain = false;
            } else if dot < zero {
                return Some(false);
            }
        }
        certain.then_some(true)
    }

    /// The triangles left by collapsing `v0 → v1` with the survivor at `target`: the faces
    /// on the edge removed, the others with both endpoints replaced by `target`; each as its
    /// corner positions, canonically rotated and the list sorted (see [`canonical`]).
    pub fn after_collapse(&self, v0: u32, v1: u32, target: Vec3) -> Vec<[[u32; 3]; 3]> {
        let at = |v: u32| {
            if v == v0 || v == v1 {
                target
            } else {
                self.positions[v as usize]
            }
        };
        canonical(
            self.triangles
                .iter()
                .filter(|t| !(t.contains(&v0) && t.contains(&v1)))
                .map(|t| t.map(at)),
        )
    }
}

/// Triangles as corner positions (bit patterns), each rotated to start at its smallest corner
/// (orientation kept), the list sorted: equal lists mean the same oriented faces.
pub fn canonical(tris: impl Iterator<Item = [Vec3; 3]>) -> Vec<[[u32; 3]; 3]> {
    let mut out: Vec<[[u32; 3]; 3]> = tris
        .map(|t| {
            let b = t.map(|p| p.to_array().map(f32::to_bits));
            (0..3)
                .map(|r| [b[r], b[(r + 1) % 3], b[(r + 2) % 3]])
                .min()
                .unwrap_or(b)
        })
        .collect();
    out.sort_unstable();
    out
}

/// Where the fold-over sign is not judged: `|old·new|` at most this fraction of
/// `|b − a|·|c − a|` of the old face times that of the new one. The rule is evaluated in
/// `f64` (a few units of `2⁻⁵³ ≈ 1.1e-16` of that scale); 1e-12 leaves four orders of
/// magnitude. Unitless.
pub const FOLD_ABSTAIN_REL: f64 = 1e-12;

/// `|b − a|·|c − a|` in `f64`.
fn edge_scale([a, b, c]: [Vec3; 3]) -> f64 {
    let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
    (b - a).length() * (c - a).length()
}

/// `(b − a) × (c − a)` in exact rational arithmetic.
fn normal([a, b, c]: [Vec3; 3]) -> [BigRational; 3] {
    let r = |x: f32| BigRational::from_float(x).unwrap_or_default();
    let sub = |p: Vec3, q: Vec3| [r(p.x) - r(q.x), r(p.y) - r(q.y), r(p.z) - r(q.z)];
    let (e1, e2) = (sub(b, a), sub(c, a));
    [
        &e1[1] * &e2[2] - &e1[2] * &e2[1],
        &e1[2] * &e2[0] - &e1[0] * &e2[2],
        &e1[0] * &e2[1] - &e1[1] * &e2[0],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use halfray_core::solids::{OCTAHEDRON_TRIANGLES, OCTAHEDRON_VERTICES};

    /// The worked cases of the rules on the octahedron (every vertex has valence 4, so the
    /// link condition holds and an edge collapse is legal at the midpoint) and on the
    /// tetrahedron (every wing has valence 3: rule 6 refuses every edge); a target far across
    /// the octahedron folds the faces over (rule 7).
    #[test]
    fn octahedron_and_tetrahedron_rules() {
        let p = OCTAHEDRON_VERTICES;
        let oct = Faces {
            positions: &p,
            triangles: &OCTAHEDRON_TRIANGLES,
        };
        let (a, b) = (OCTAHEDRON_TRIANGLES[0][0], OCTAHEDRON_TRIANGLES[0][1]);
        let mid = (p[a as usize] + p[b as usize]) * 0.5;
        assert_eq!(oct.may_collapse(a, b, mid), Some(true));
        assert_eq!(oct.may_collapse(a, b, -p[a as usize] * 4.0), Some(false));
        assert_eq!(oct.after_collapse(a, b, mid).len(), 6);
        let tp = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let tt = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
        let tet = Faces {
            positions: &tp,
            triangles: &tt,
        };
        assert_eq!(tet.may_collapse(0, 1, Vec3::ZERO), Some(false));
    }
}
