//! Plugin objects with typed, located properties (as Mitsuba's `Properties` and pbrt-v4's
//! `ParameterDictionary`): what every scene format's loader produces and every plugin constructs
//! itself from. A property getter checks the value's type, marks the property as read (so that
//! parameters no plugin reads are errors, as in Mitsuba 3) and reports problems at the
//! property's `file:line:col`.

pub mod error;
pub mod fov;
mod get;
pub mod value;

pub use error::{nearest, Loc, SceneError, SourceFile};
pub use value::{Obj, Prop, SpectrumValue, Value, OBJECT_TAGS};

/// Results of building plugins from properties.
pub type Result<T> = std::result::Result<T, SceneError>;
