//! The skin resolver's state; its steps are methods in the sibling files.

use std::ops::{Deref, DerefMut};

use crate::spec::check::Ctx;

/// The skin resolver: the shared checks ([`Ctx`], reached through `Deref`) and the skin's own
/// steps, in this module and its siblings.
pub(super) struct SkinCx {
    cx: Ctx,
}

impl Deref for SkinCx {
    type Target = Ctx;
    fn deref(&self) -> &Ctx {
        &self.cx
    }
}

impl DerefMut for SkinCx {
    fn deref_mut(&mut self) -> &mut Ctx {
        &mut self.cx
    }
}

impl SkinCx {
    pub(super) fn new(file: &str) -> SkinCx {
        SkinCx { cx: Ctx::new(file) }
    }
}
