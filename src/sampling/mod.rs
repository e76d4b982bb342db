//! Sampling layer: warps from uniform random numbers to the distributions light transport
//! needs, 1D/2D tabulated distributions, MIS heuristics, the RNG and the samplers.
//!
//! Conventions (pbrt-v4 style, see `../shared/docs/design.md`):
//! - Every routine takes its uniform random numbers `u ∈ [0,1)ᵈ` as arguments; none draws them
//!   itself (the rejection sampler, which needs an unbounded supply, takes a generator closure).
//! - Warps come as `sample_x(u) -> Sample<T>` (value and pdf with its [`Measure`]),
//!   `x_pdf(value) -> f32`, and `invert_x(value) -> u` where an inverse exists.
//! - Directions are in the local frame: +z is the normal (see [`crate::math::Frame`]).
//!
//! Where to find things:
//!
//! | distribution | file |
//! |---|---|
//! | uniform disk (polar `r=√ξ₁, φ=2πξ₂`; concentric) | [`disk`] |
//! | uniform / cosine-weighted hemisphere (Malley; inversion `θ=asin √ξ₁`) | [`hemisphere`] |
//! | uniform sphere, spherical cap (cone) | [`sphere`] |
//! | equal-area octahedral square ↔ sphere (pbrt-v4's environment maps) | [`equal_area`] |
//! | uniform triangle (`u=1-√(1-ξ₁), v=ξ₂√(1-ξ₁)`) | [`triangle`] |
//! | power `(n+1)xⁿ`, cosine-power lobe | [`power`] |
//! | exponential `a e^(-ax)` | [`exponential`] |
//! | rejection sampling | [`rejection`] |
//! | discrete by CDF + binary search; alias table | [`discrete`], [`alias`] |
//! | piecewise-constant 1D and 2D (marginal/conditional) | [`piecewise1d`], [`piecewise2d`] |
//! | piecewise-linear 1D (tabulated phase functions) | [`piecewise_linear`] |
//! | bilinearly interpolated 2D, conditioned on parameters (Mitsuba's `Marginal2D`; measured BSDFs) | [`marginal2d`] |
//! | MIS heuristics | [`mis`] |
//! | PCG32, hashing, samplers (independent, stratified, Owen-scrambled Sobol) | [`rng`], [`hash`], [`sampler`] |

pub mod alias;
pub mod discrete;
pub mod disk;
pub mod equal_area;
pub mod exponential;
pub mod hash;
pub mod hemisphere;
pub mod marginal2d;
mod measure;
pub mod mis;
pub mod piecewise1d;
pub mod piecewise2d;
pub mod piecewise_linear;
pub mod power;
pub mod rejection;
pub mod rng;
pub mod sampler;
pub mod sphere;
pub mod triangle;

pub use alias::AliasTable;
pub use discrete::DiscreteCdf;
pub use disk::*;
pub use exponential::*;
pub use hemisphere::*;
pub use marginal2d::Marginal2D;
pub use measure::{area_to_solid_angle, solid_angle_to_area, Measure, Sample};
pub use mis::{balance_heuristic, power_heuristic};
pub use piecewise1d::PiecewiseConstant1D;
pub use piecewise2d::PiecewiseConstant2D;
pub use piecewise_linear::PiecewiseLinear1D;
pub use power::*;
pub use rejection::{sample_rejection, sample_uniform_disk_rejection, RejectionSample};
pub use rng::{Pcg32, Stride};
pub use sampler::Sampler;
pub use sphere::*;
pub use triangle::*;
