//! The three 2-D edge functions of a triangle sheared by a [`super::WatertightRay`]
//! ([`edges`]): in plain `f32`, the watertight family's filter ([`filter_edges`], whose
//! certain signs are exact), and exact in `f64` ([`exact_edges`]); and the test that rejects a
//! triangle on its `f32` signs ([`mixed_signs`]).

use crate::float::{diff_of_products_exact_sign, diff_of_products_sign_filter};

/// The three edge functions `e0 = c_x·b_y − c_y·b_x`, `e1 = a_x·c_y − a_y·c_x`,
/// `e2 = b_x·a_y − b_y·a_x` of the sheared 2-D vertices `x`, `y`, each evaluated as
/// `diff(p, q, r, s) = p·q − r·s` (the evaluation decides the precision).
#[inline(always)]
fn edges<T>(x: [f32; 3], y: [f32; 3], diff: impl Fn(f32, f32, f32, f32) -> T) -> [T; 3] {
    let ([ax, bx, cx], [ay, by, cy]) = (x, y);
    [
        diff(cx, by, cy, bx),
        diff(ax, cy, ay, cx),
        diff(bx, ay, by, ax),
    ]
}

/// The edge functions of [`edges`] in plain `f32`: the filter of the watertight family, whose
/// signs are exact wherever non-zero and not NaN ([`diff_of_products_sign_filter`]).
#[inline(always)]
pub(in crate::triangle) fn filter_edges(x: [f32; 3], y: [f32; 3]) -> [f32; 3] {
    edges(x, y, diff_of_products_sign_filter)
}

/// The edge functions of [`edges`], each the `f64` difference of exact `f64` products:
/// exact signs, and zero exactly on the edge ([`diff_of_products_exact_sign`]).
#[inline(always)]
pub(super) fn exact_edges(x: [f32; 3], y: [f32; 3]) -> [f64; 3] {
    edges(x, y, diff_of_products_exact_sign)
}

/// `true` when `e` holds both a negative and a positive value (zeros and NaN count as
/// neither): the ray passes outside the triangle.
#[inline(always)]
pub(in crate::triangle) fn mixed_signs(e: &[f32; 3]) -> bool {
    let neg = (e[0] < 0.0) | (e[1] < 0.0) | (e[2] < 0.0);
    let pos = (e[0] > 0.0) | (e[1] > 0.0) | (e[2] > 0.0);
    neg & pos
}
