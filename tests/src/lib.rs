//! clothlab-tests: tests that span backends (GPU vs CPU, golden images, soak runs), and
//! the comparison helpers they share with `clothlab validate`.
//!
//! GPU tests run wherever an adapter exists (Mesa's lavapipe counts). Without one they
//! print why and pass, unless `CLOTHLAB_REQUIRE_GPU=1` (CI sets it), which makes a
//! missing adapter a failure.
#![forbid(unsafe_code)]

use clothlab_core::grid::V4;

/// Largest absolute difference over the xyz components, and the largest |reference|.
pub fn max_abs_diff(got: &[V4], want: &[V4]) -> (f32, f32) {
    assert_eq!(got.len(), want.len(), "buffer lengths differ");
    let mut diff = 0.0f32;
    let mut scale = 0.0f32;
    for (g, w) in got.iter().zip(want) {
        for k in 0..3 {
            let d = (g[k] - w[k]).abs();
            // A NaN (an unwritten, poisoned element) must fail, not compare as 0.
            diff = if d.is_nan() { f32::INFINITY } else { diff.max(d) };
            if diff.is_infinite() {
                return (f32::INFINITY, scale);
            }
            scale = scale.max(w[k].abs());
        }
    }
    (diff, scale)
}

/// `max |got - want| / max |want|` over xyz: the error relative to the buffer's scale.
pub fn rel_error(got: &[V4], want: &[V4]) -> f32 {
    let (d, s) = max_abs_diff(got, want);
    if s == 0.0 { d } else { d / s }
}

/// Whether GPU tests must fail rather than skip without an adapter.
pub fn gpu_required() -> bool {
    std::env::var("CLOTHLAB_REQUIRE_GPU").is_ok_and(|v| v == "1")
}
