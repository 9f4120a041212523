//! Where shapes come from: procedural shapes of every category plus, optionally, a bank of real
//! meshes; split into train and validation **by shape** (never by pair).
//!
//! * Procedural train shapes use generator seeds below [`VAL_SEED_BASE`]; validation shapes use
//!   the `val_procedural_per_category` seeds from [`VAL_SEED_BASE`] on, so no validation shape is
//!   ever a training shape.
//! * Bank shapes are split by [`super::bank::split_of`] (a hash of the relative path).
//! * Pair `index` of a split picks its shape and its pair seed deterministically from
//!   `(split, index)`, so a validation set is a fixed list and a training stream is reproducible.

use super::bank::{split_of, Bank, NamedMesh};
use super::mix;
use super::pairs::{make_pair, Pair, PairParams};
use super::shapes::{generate, Category, CATEGORIES};
use crate::io::Mesh;
use crate::Result;
use std::borrow::Cow;

/// Training or validation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Split {
    /// Training shapes.
    Train,
    /// Held-out validation shapes.
    Val,
}

impl Split {
    fn tag(self) -> u64 {
        match self {
            Split::Train => 0x7EA1,
            Split::Val => 0x0FA1,
        }
    }
}

/// Procedural generator seeds from here on are validation shapes; below are training shapes.
pub const VAL_SEED_BASE: u64 = 1 << 40;

/// Procedural and bank shapes, with a shape-level split.
#[derive(Clone, Debug)]
pub struct ShapeSource {
    /// Bank meshes of the training split.
    pub bank_train: Vec<NamedMesh>,
    /// Bank meshes of the validation split.
    pub bank_val: Vec<NamedMesh>,
    /// Probability that a pair uses a bank shape when the split has any (default 0.3).
    pub bank_fraction: f64,
    /// Use procedural shapes (default true). With `false`, only bank shapes are used.
    pub procedural: bool,
    /// Number of distinct procedural training shapes per category; `None` (default) = a new
    /// shape for every pair (an unbounded stream).
    pub train_procedural_per_category: Option<u64>,
    /// Number of procedural validation shapes per category (default 10, i.e. 200 shapes).
    pub val_procedural_per_category: u64,
}

impl Default for ShapeSource {
    fn default() -> Self {
        Self {
            bank_train: Vec::new(),
            bank_val: Vec::new(),
            bank_fraction: 0.3,
            procedural: true,
            train_procedural_per_category: None,
            val_procedural_per_category: 10,
        }
    }
}

/// A shape: its name and mesh (borrowed from the bank, or freshly generated).
pub struct ShapeRef<'a> {
    /// `procedural/<category>/<seed>` or `bank/<relative path>`.
    pub name: String,
    /// The mesh.
    pub mesh: Cow<'a, Mesh>,
}

impl ShapeSource {
    /// Procedural shapes only.
    pub fn procedural() -> Self {
        Self::default()
    }

    /// Procedural shapes plus a bank split by shape, `val_fraction` of it held out.
    pub fn with_bank(bank: Bank, val_fraction: f64) -> Self {
        let mut s = Self::default();
        for m in bank.meshes {
            match split_of(&m.name, val_fraction) {
                Split::Train => s.bank_train.push(m),
                Split::Val => s.bank_val.push(m),
            }
        }
        s
    }

    fn bank(&self, split: Split) -> &[NamedMesh] {
        match split {
            Split::Train => &self.bank_train,
            Split::Val => &self.bank_val,
        }
    }

    /// The procedural `(category, generator seed)` of the `k`-th procedural shape of a split.
    pub fn procedural_id(&self, split: Split, k: u64) -> (Category, u64) {
        let cat = CATEGORIES[(k % CATEGORIES.len() as u64) as usize];
        let j = k / CATEGORIES.len() as u64;
        let seed = match split {
            Split::Train => match self.train_procedural_per_category {
                Some(n) => j % n.max(1),
                None => j % VAL_SEED_BASE,
            },
            Split::Val => VAL_SEED_BASE + j % self.val_procedural_per_category.max(1),
        };
        (cat, seed)
    }

    /// The shape of pair `index` of a split. Fails if the split has no shapes at all.
    pub fn shape(&self, split: Split, index: u64) -> Result<ShapeRef<'_>> {
        let bank = self.bank(split);
        let h = mix(index, split.tag());
        let use_bank = !bank.is_empty() && (!self.procedural || super::unit_of_hash(h) < self.bank_fraction);
        if use_bank {
            let m = &bank[(mix(h, 0xBA4C) % bank.len() as u64) as usize];
            return Ok(ShapeRef { name: format!("bank/{}", m.name), mesh: Cow::Borrowed(&m.mesh) });
        }
        if !self.procedural {
            return Err(crate::Error::InvalidOption(format!(
                "no shapes: procedural shapes are off and the bank has no {split:?} meshes"
            )));
        }
        let (cat, seed) = self.procedural_id(split, index);
        Ok(ShapeRef { name: format!("procedural/{}/{seed}", cat.name()), mesh: Cow::Owned(generate(cat, seed)) })
    }

    /// Pair `index` of a split: its shape ([`Self::shape`]) and the protocol with the pair seed
    /// `mix(index, split)`.
    pub fn pair(&self, split: Split, index: u64, params: &PairParams) -> Result<Pair> {
        let shape = self.shape(split, index)?;
        make_pair(&shape.mesh, &shape.name, params, mix(index, split.tag() ^ 0x9A12))
    }
}
