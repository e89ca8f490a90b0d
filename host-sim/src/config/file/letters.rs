//! Machine-file keys per axis letter: the file names every letter of
//! grblHAL's six (`protocol::ALL_AXIS_NAMES`), the build drives the first
//! [`AXES`]; the rest are refused by their key.

use super::super::ConfigError;
use burin::{AXES, AXIS_NAMES};

macro_rules! axis_keys {
    ($l:literal) => {
        [
            concat!("axes.", $l, ".steps_per_mm"),
            concat!("axes.", $l, ".max_rate_mm_min"),
            concat!("axes.", $l, ".max_accel_mm_s2"),
            concat!("axes.", $l, ".travel_mm"),
            concat!("axes.", $l, ".backlash_mm"),
            concat!("axes.", $l, ".slack_mm"),
        ]
    };
}

/// Key names used in error messages, per axis letter in
/// `protocol::ALL_AXIS_NAMES` order; the first [`AXES`] are this build's.
const ALL_AXIS_KEYS: [[&str; 6]; 6] = [
    axis_keys!("x"),
    axis_keys!("y"),
    axis_keys!("z"),
    axis_keys!("a"),
    axis_keys!("b"),
    axis_keys!("c"),
];
pub(super) const ALL_TRIP_KEYS: [&str; 6] = [
    "limits.x_trip_mm",
    "limits.y_trip_mm",
    "limits.z_trip_mm",
    "limits.a_trip_mm",
    "limits.b_trip_mm",
    "limits.c_trip_mm",
];
pub(in crate::config) const AXIS_KEYS: [[&str; 6]; AXES] = protocol::first_axes(ALL_AXIS_KEYS);
pub(in crate::config) const TRIP_KEYS: [&str; AXES] = protocol::first_axes(ALL_TRIP_KEYS);

/// Per-letter values of a file (one per `protocol::ALL_AXIS_NAMES` letter)
/// as this build's axes; a value for a letter past [`AXES`] is refused,
/// so a six-axis file is not run on fewer axes as if it fitted.
pub(super) fn driven<T>(
    all: [Option<T>; 6],
    keys: [&str; 6],
) -> Result<[Option<T>; AXES], ConfigError> {
    if let Some(i) = all.iter().skip(AXES).position(Option::is_some) {
        return Err(ConfigError::invalid(
            keys[AXES + i],
            format!(
                "this build drives {AXES} axes ({})",
                String::from_iter(AXIS_NAMES)
            ),
        ));
    }
    let mut it = all.into_iter();
    Ok(core::array::from_fn(|_| it.next().flatten()))
}
