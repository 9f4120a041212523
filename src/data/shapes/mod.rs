//! Procedural ModelNet-like objects in the 20 ModelNet20 categories.
//!
//! [`generate`] assembles a triangle mesh from parametric parts ([`parts`]: boxes, frusta,
//! ellipsoids, tori, lathe profiles, extrusions, rods) with proportions, part counts and
//! placements drawn from a seed, so every `(category, seed)` is a distinct, reproducible shape.
//! Shapes are in metres-ish units with z up; the pair generator normalises them anyway. Parts
//! overlap rather than being merged (a triangle soup of closed parts), which is all surface
//! sampling needs. Where the real category has a well-defined pose (a cup's handle, a desk's
//! pedestal, a door's handle) so do the generated shapes; bottles, bowls and cones stay (nearly)
//! rotationally symmetric as real ones are.

pub mod parts;

mod furniture;
mod household;
mod vehicles;
mod vessels;

use crate::io::Mesh;
use parts::Dice;

/// A ModelNet20 category (the first 20 ModelNet40 classes, alphabetical).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Category {
    /// Airliners and propeller planes.
    Airplane,
    /// Open tubs, with feet and a faucet sometimes.
    Bathtub,
    /// Frame, mattress, headboard, pillows.
    Bed,
    /// Seats with legs, backrests and armrests sometimes.
    Bench,
    /// Shelves with books.
    Bookshelf,
    /// Revolved bottles, with caps, labels, handles.
    Bottle,
    /// Revolved bowls with a foot ring.
    Bowl,
    /// Sedans, hatchbacks, SUVs, pickups.
    Car,
    /// Four-legged or swivel chairs.
    Chair,
    /// Traffic cones and plain cones.
    Cone,
    /// Cups with a handle.
    Cup,
    /// Folded curtains on a rod.
    Curtain,
    /// Desks with a drawer pedestal.
    Desk,
    /// Doors with panels, handle and hinges.
    Door,
    /// Chests of drawers.
    Dresser,
    /// Pots with plants.
    FlowerPot,
    /// Glass display cases and aquariums.
    GlassBox,
    /// Acoustic and electric guitars.
    Guitar,
    /// Computer keyboards.
    Keyboard,
    /// Standing and desk lamps.
    Lamp,
}

/// All 20 categories, in ModelNet order.
pub const CATEGORIES: [Category; 20] = [
    Category::Airplane,
    Category::Bathtub,
    Category::Bed,
    Category::Bench,
    Category::Bookshelf,
    Category::Bottle,
    Category::Bowl,
    Category::Car,
    Category::Chair,
    Category::Cone,
    Category::Cup,
    Category::Curtain,
    Category::Desk,
    Category::Door,
    Category::Dresser,
    Category::FlowerPot,
    Category::GlassBox,
    Category::Guitar,
    Category::Keyboard,
    Category::Lamp,
];

impl Category {
    /// The ModelNet name (`flower_pot`, `glass_box`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Category::Airplane => "airplane",
            Category::Bathtub => "bathtub",
            Category::Bed => "bed",
            Category::Bench => "bench",
            Category::Bookshelf => "bookshelf",
            Category::Bottle => "bottle",
            Category::Bowl => "bowl",
            Category::Car => "car",
            Category::Chair => "chair",
            Category::Cone => "cone",
            Category::Cup => "cup",
            Category::Curtain => "curtain",
            Category::Desk => "desk",
            Category::Door => "door",
            Category::Dresser => "dresser",
            Category::FlowerPot => "flower_pot",
            Category::GlassBox => "glass_box",
            Category::Guitar => "guitar",
            Category::Keyboard => "keyboard",
            Category::Lamp => "lamp",
        }
    }

    /// The category with this ModelNet name.
    pub fn from_name(name: &str) -> Option<Category> {
        CATEGORIES.iter().copied().find(|c| c.name() == name)
    }

    /// Position in [`CATEGORIES`].
    pub fn index(self) -> usize {
        CATEGORIES.iter().position(|&c| c == self).unwrap_or(0)
    }
}

impl std::fmt::Display for Category {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A new shape of `category`, reproducible from `seed` (on every platform).
///
/// After assembly each axis is scaled by a factor in [0.9, 1.1] for extra variety.
pub fn generate(category: Category, seed: u64) -> Mesh {
    let mut r = Dice::new(super::mix(seed, 0xC47E_6012 ^ category.index() as u64));
    let mut mesh = match category {
        Category::Airplane => vehicles::airplane(&mut r),
        Category::Bathtub => furniture::bathtub(&mut r),
        Category::Bed => furniture::bed(&mut r),
        Category::Bench => furniture::bench(&mut r),
        Category::Bookshelf => furniture::bookshelf(&mut r),
        Category::Bottle => vessels::bottle(&mut r),
        Category::Bowl => vessels::bowl(&mut r),
        Category::Car => vehicles::car(&mut r),
        Category::Chair => furniture::chair(&mut r),
        Category::Cone => vessels::cone(&mut r),
        Category::Cup => vessels::cup(&mut r),
        Category::Curtain => household::curtain(&mut r),
        Category::Desk => furniture::desk(&mut r),
        Category::Door => furniture::door(&mut r),
        Category::Dresser => furniture::dresser(&mut r),
        Category::FlowerPot => vessels::flower_pot(&mut r),
        Category::GlassBox => household::glass_box(&mut r),
        Category::Guitar => household::guitar(&mut r),
        Category::Keyboard => household::keyboard(&mut r),
        Category::Lamp => vessels::lamp(&mut r),
    };
    let k = [r.u(0.9, 1.1), r.u(0.9, 1.1), r.u(0.9, 1.1)];
    for p in &mut mesh.vertices {
        for a in 0..3 {
            p[a] *= k[a] as f32;
        }
    }
    mesh
}
