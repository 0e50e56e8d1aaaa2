//! Run-time dispatch to AVX2: `avx2_dispatch!` defines a function that calls its
//! `#[inline(always)]` body from a copy compiled with AVX2 enabled where the processor has
//! it, so the body's loops vectorise 4 lanes wide (f64) or 8 (f32) instead of the baseline's
//! 2 or 4.
//!
//! The bodies it is used with are written with the same IEEE operations in every lane and no
//! fused multiply-add, so both paths give the same bits on every x86-64 machine: the tables a
//! bake writes do not depend on the processor it ran on.
//!
//! A macro rather than a function taking a closure: a closure's body is not reliably inlined
//! into a `#[target_feature]` function, and where it is not, it runs without AVX2 (measured:
//! `FacetPdf::eval_many` lost its 8-lane loop that way). The function this defines names its
//! arguments, as the hand-written dispatch did, so the body is compiled into the AVX2 copy.

/// `avx2_dispatch! { /// docs
/// pub fn name(a: A, b: B) -> R => body_fn }` defines `name`, which runs `body_fn(a, b)` in a
/// copy compiled for AVX2 where the processor has it (`std`'s cached feature detection), else
/// directly. For a method, the receiver comes first as `&self as Type` and `body_fn` is a path
/// such as `Type::method_in`. `body_fn` should be `#[inline(always)]`.
macro_rules! avx2_dispatch {
    (
        $(#[$meta:meta])*
        $vis:vis fn $name:ident(&self as $self_ty:ty $(, $arg:ident: $ty:ty)* $(,)?)
            $(-> $ret:ty)? => $body:path
    ) => {
        $(#[$meta])*
        $vis fn $name(&self $(, $arg: $ty)*) $(-> $ret)? {
            let this = self;
            avx2_dispatch!(@call $body; ($($ret)?); this: &$self_ty $(, $arg: $ty)*)
        }
    };
    (
        $(#[$meta:meta])*
        $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? => $body:path
    ) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) $(-> $ret)? {
            avx2_dispatch!(@call $body; ($($ret)?); $($arg: $ty),*)
        }
    };
    // The dispatch both forms share: `$body(args…)` from an AVX2 copy, else directly.
    (@call $body:path; ($($ret:ty)?); $($arg:ident: $ty:ty),*) => {{
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            #[target_feature(enable = "avx2")]
            fn avx2($($arg: $ty),*) $(-> $ret)? {
                $body($($arg),*)
            }
            // SAFETY: the processor has AVX2 (checked above).
            return unsafe { avx2($($arg),*) };
        }
        $body($($arg),*)
    }};
}

pub(crate) use avx2_dispatch;

#[cfg(test)]
mod tests {
    // `avx2_dispatch!` is in scope textually (defined above in this file).

    #[inline(always)]
    fn sum_in(x: &[f64], scale: f64) -> f64 {
        x.iter().map(|v| v * scale).sum()
    }

    avx2_dispatch! {
        fn sum(x: &[f64], scale: f64) -> f64 => sum_in
    }

    struct Scaled(f64);

    impl Scaled {
        #[inline(always)]
        fn apply_in(&self, out: &mut [f64]) {
            for o in out {
                *o *= self.0;
            }
        }

        avx2_dispatch! {
            fn apply(&self as Scaled, out: &mut [f64]) => Scaled::apply_in
        }
    }

    #[test]
    fn both_forms_give_the_body_s_result() {
        let x: Vec<f64> = (0..37).map(|i| i as f64 * 0.25).collect();
        assert_eq!(sum(&x, 2.0), sum_in(&x, 2.0));
        let mut a = x.clone();
        Scaled(3.0).apply(&mut a);
        assert!(a.iter().zip(&x).all(|(a, x)| *a == 3.0 * x));
    }
}
