//! The operations the AVX2 copies of the lanes' query spell out (four `f64` lanes a
//! `__m256d`), as macros: a helper closure inside a `#[target_feature(enable = "avx2")]`
//! function is compiled without AVX2 and is not always inlined there, a macro always is. Each
//! is the IEEE operation, or the comparison Rust's operator makes, lane by lane; a use site
//! brings `std::arch::x86_64::*` into scope.

/// `x` in every lane.
macro_rules! splat {
    ($x:expr $(,)?) => {
        _mm256_set1_pd($x)
    };
}

/// `a + b`, `a − b`, `a · b`, `a / b`.
macro_rules! add {
    ($a:expr, $b:expr $(,)?) => {
        _mm256_add_pd($a, $b)
    };
}
macro_rules! sub {
    ($a:expr, $b:expr $(,)?) => {
        _mm256_sub_pd($a, $b)
    };
}
macro_rules! mul {
    ($a:expr, $b:expr $(,)?) => {
        _mm256_mul_pd($a, $b)
    };
}
macro_rules! div {
    ($a:expr, $b:expr $(,)?) => {
        _mm256_div_pd($a, $b)
    };
}

/// `|v|`.
macro_rules! abs {
    ($v:expr $(,)?) => {
        _mm256_and_pd($v, _mm256_castsi256_pd(_mm256_set1_epi64x(i64::MAX)))
    };
}

/// Masks (all ones where true): `a & b`, `a | b`, `!a`.
macro_rules! and {
    ($a:expr, $b:expr $(,)?) => {
        _mm256_and_pd($a, $b)
    };
}
macro_rules! or {
    ($a:expr, $b:expr $(,)?) => {
        _mm256_or_pd($a, $b)
    };
}
macro_rules! not {
    ($a:expr $(,)?) => {
        _mm256_xor_pd($a, _mm256_castsi256_pd(_mm256_set1_epi64x(-1)))
    };
}

/// `if m { a } else { b }` lane by lane.
macro_rules! pick {
    ($m:expr, $a:expr, $b:expr $(,)?) => {
        _mm256_blendv_pd($b, $a, $m)
    };
}

/// Rust's `a < b`, `a <= b`, `a > b`, `a >= b`, `a == b` (false for a NaN) and `a != b`
/// (true for a NaN), as masks.
macro_rules! lt {
    ($a:expr, $b:expr $(,)?) => {
        _mm256_cmp_pd::<_CMP_LT_OQ>($a, $b)
    };
}
macro_rules! le {
    ($a:expr, $b:expr $(,)?) => {
        _mm256_cmp_pd::<_CMP_LE_OQ>($a, $b)
    };
}
macro_rules! gt {
    ($a:expr, $b:expr $(,)?) => {
        _mm256_cmp_pd::<_CMP_GT_OQ>($a, $b)
    };
}
macro_rules! ge {
    ($a:expr, $b:expr $(,)?) => {
        _mm256_cmp_pd::<_CMP_GE_OQ>($a, $b)
    };
}
macro_rules! eq {
    ($a:expr, $b:expr $(,)?) => {
        _mm256_cmp_pd::<_CMP_EQ_OQ>($a, $b)
    };
}
macro_rules! ne {
    ($a:expr, $b:expr $(,)?) => {
        _mm256_cmp_pd::<_CMP_NEQ_UQ>($a, $b)
    };
}

/// `v.is_finite()`, as a mask.
macro_rules! finite {
    ($v:expr $(,)?) => {
        lt!(abs!($v), splat!(f64::INFINITY))
    };
}
