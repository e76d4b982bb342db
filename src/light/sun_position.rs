//! Where the sun stands in the sky at a date, time and place: the algorithm of Blanco-Muriel,
//! Alarcón-Padilla, López-Moratalla and Lara-Coira, "Computing the solar vector" (Solar
//! Energy 70(5), 2001), as Mitsuba 3's `sunsky` emitter evaluates it, in single precision
//! (Mitsuba's scalar and LLVM variants compute in `f32`: the Julian date is then rounded to a
//! quarter day, which moves the sun by about a tenth of a degree; neumann rounds the same way so
//! that a scene's sun stands where Mitsuba puts it).
//!
//! Frame: the emitter's local frame, +z the zenith, azimuth measured from +x towards +y; the
//! returned direction points from the ground towards the sun.

use crate::math::Vec3;

/// A place on Earth: degrees north and east, and the hours its clock is ahead of UTC.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Location {
    /// Degrees north (negative: south).
    pub latitude: f32,
    /// Degrees east (negative: west).
    pub longitude: f32,
    /// Hours ahead of UTC.
    pub timezone: f32,
}

/// A local date and time (the clock of [`Location::timezone`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DateTime {
    /// Year.
    pub year: i32,
    /// Month, 1–12.
    pub month: i32,
    /// Day of the month.
    pub day: i32,
    /// Hour (fractional hours allowed).
    pub hour: f32,
    /// Minute.
    pub minute: f32,
    /// Second.
    pub second: f32,
}

/// Mitsuba's defaults: Tokyo (35.6894° N, 139.6917° E, UTC+9).
impl Default for Location {
    fn default() -> Location {
        Location { latitude: 35.6894, longitude: 139.6917, timezone: 9.0 }
    }
}

/// Mitsuba's defaults: 10 July 2010, 15:00.
impl Default for DateTime {
    fn default() -> DateTime {
        DateTime { year: 2010, month: 7, day: 10, hour: 15.0, minute: 0.0, second: 0.0 }
    }
}

/// Mean radius of the Earth over the astronomical unit (both in km): the parallax correction.
const EARTH_OVER_AU: f64 = 6371.01 / 149_597_890.0;

/// The Julian day number of a civil date (the day starting at noon of that date), with
/// Mitsuba's integer arithmetic (truncating division), in 64 bits so that no year overflows;
/// a day past the month's end rolls over into the next month.
pub fn day_number(year: i32, month: i32, day: i32) -> i64 {
    let (year, month, day) = (year as i64, month as i64, day as i64);
    let aux1 = (month - 14) / 12;
    (1461 * (year + 4800 + aux1)) / 4 + (367 * (month - 2 - 12 * aux1)) / 12 - (3 * ((year + 4900 + aux1) / 100)) / 4
        + day
        - 32075
}

/// The sun's zenith angle θ and azimuth φ (radians) at `time` in `place`, as Mitsuba's
/// `sun_coordinates` returns them (φ measured from +x, the algorithm's azimuth less π). The
/// algorithm's constants are written as published (more digits than `f32` holds).
#[allow(clippy::excessive_precision)]
pub fn sun_angles(time: &DateTime, place: &Location) -> (f32, f32) {
    // Time of day in UT decimal hours, and days since JD 2451545.0 (noon, 1 January 2000).
    let dec_hours = time.hour - place.timezone + (time.minute + time.second / 60.0) / 60.0;
    let julian_date = day_number(time.year, time.month, time.day) as f32 - 0.5 + dec_hours / 24.0;
    let days = julian_date - 2_451_545.0;

    // Ecliptic coordinates (radians, not reduced to [0, 2π)).
    let omega = 2.1429f32 - 0.001_039_459_4 * days;
    let mean_longitude = 4.895_063f32 + 0.017_202_791_698 * days;
    let anomaly = 6.240_06f32 + 0.017_201_969_9 * days;
    let ecliptic_longitude = mean_longitude + 0.033_416_07 * anomaly.sin() + 0.000_348_94 * (2.0 * anomaly).sin()
        - 0.000_113_4
        - 0.000_020_3 * omega.sin();
    let obliquity = 0.409_092_8f32 - 6.2140e-9 * days + 0.000_039_6 * omega.cos();

    // Celestial coordinates.
    let sin_longitude = ecliptic_longitude.sin();
    let mut right_ascension = (obliquity.cos() * sin_longitude).atan2(ecliptic_longitude.cos());
    if right_ascension < 0.0 {
        right_ascension += 2.0 * std::f32::consts::PI;
    }
    let declination = (obliquity.sin() * sin_longitude).asin();

    // Local coordinates.
    let gmst = 6.697_424_3f32 + 0.065_709_83 * days + dec_hours;
    let lmst = (gmst * 15.0 + place.longitude).to_radians();
    let latitude = place.latitude.to_radians();
    let (sin_lat, cos_lat) = latitude.sin_cos();
    let hour_angle = lmst - right_ascension;
    let cos_hour = hour_angle.cos();
    let mut zenith = (cos_lat * cos_hour * declination.cos() + declination.sin() * sin_lat).acos();
    let mut azimuth = (-hour_angle.sin()).atan2(declination.tan() * cos_lat - sin_lat * cos_hour);
    if azimuth < 0.0 {
        azimuth += 2.0 * std::f32::consts::PI;
    }
    zenith += EARTH_OVER_AU as f32 * zenith.sin();
    (zenith, azimuth - std::f32::consts::PI)
}

/// Unit direction towards the sun (local frame, +z up) at `time` in `place`.
pub fn sun_direction(time: &DateTime, place: &Location) -> Vec3 {
    let (theta, phi) = sun_angles(time, place);
    let (sin_theta, cos_theta) = theta.sin_cos();
    let (sin_phi, cos_phi) = phi.sin_cos();
    Vec3::new(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta)
}

#[cfg(test)]
#[allow(clippy::excessive_precision)]
mod tests {
    use super::*;

    /// The sun's direction where Mitsuba 3.9.1 puts it (`tools/mitsuba/sunsky_values.py`, the
    /// emitters given by time and place): Mitsuba's defaults (Tokyo, 10 July 2010, 15:00), Paris
    /// on the March equinox of 2024 at 10:00:12, and Cape Town on the last evening of 1999.
    #[test]
    fn matches_mitsuba() {
        let cases = [
            (DateTime::default(), Location::default(), Vec3::new(5.138_544_7e-2, 6.917_479_6e-1, 7.203_084_8e-1)),
            (
                DateTime { year: 2024, month: 3, day: 20, hour: 9.5, minute: 30.0, second: 12.0 },
                Location { latitude: 48.85, longitude: 2.35, timezone: 1.0 },
                Vec3::new(5.360_416_2e-1, -7.000_268_7e-1, 4.718_280_7e-1),
            ),
            (
                DateTime { year: 1999, month: 12, day: 31, hour: 17.0, minute: 0.0, second: 0.0 },
                Location { latitude: -33.9, longitude: 18.4, timezone: 2.0 },
                Vec3::new(9.043_577_3e-2, 8.173_087_2e-1, 5.690_586_6e-1),
            ),
        ];
        for (time, place, expected) in cases {
            let d = sun_direction(&time, &place);
            assert!((d - expected).length() < 2e-5, "{time:?} {place:?}: {d} against {expected}");
        }
    }

    /// Days past the end of a month roll over (the Julian-day formula's own arithmetic, as in
    /// Mitsuba, which checks no ranges), and no year overflows.
    #[test]
    fn days_roll_over_and_years_do_not_overflow() {
        let place = Location::default();
        let feb14 = DateTime { year: 2021, month: 2, day: 14, hour: 10.0, minute: 0.0, second: 0.0 };
        let jan45 = DateTime { month: 1, day: 45, ..feb14 };
        assert_eq!(sun_direction(&feb14, &place), sun_direction(&jan45, &place));
        for year in [i32::MIN, -4713, i32::MAX] {
            assert!(sun_direction(&DateTime { year, ..feb14 }, &place).is_finite());
        }
    }

    /// Independent sanity: at the equator on an equinox the noon sun stands near the zenith,
    /// and at midnight it is below the horizon; the June sun at 60° N culminates about 53.5°
    /// above the horizon (90° − 60° + 23.44°).
    #[test]
    fn physical_positions() {
        let equator = Location { latitude: 0.0, longitude: 0.0, timezone: 0.0 };
        let noon = DateTime { year: 2021, month: 3, day: 20, hour: 12.0, minute: 0.0, second: 0.0 };
        assert!(sun_direction(&noon, &equator).z > 0.99);
        assert!(sun_direction(&DateTime { hour: 0.0, ..noon }, &equator).z < -0.99);
        let north = Location { latitude: 60.0, longitude: 0.0, timezone: 0.0 };
        let june = DateTime { year: 2021, month: 6, day: 21, hour: 12.0, minute: 0.0, second: 0.0 };
        let elevation = sun_direction(&june, &north).z.asin().to_degrees();
        assert!((elevation - 53.5).abs() < 0.6, "{elevation}");
    }
}
