//! The sun's position in the sky from date, time and place.
//!
//! The algorithm is the NOAA Solar Calculator's, after J. Meeus,
//! *Astronomical Algorithms* (Willmann-Bell, 1991), chapters 7 (Julian day),
//! 25 (solar coordinates, low accuracy) and 28 (equation of time): the
//! geometric mean longitude and anomaly of the sun, the equation of the
//! centre, the apparent longitude (nutation and aberration by the `Omega`
//! term), the obliquity of the ecliptic, then the declination and the
//! equation of time, the true solar time, the hour angle, and the altitude
//! and azimuth. It is good to about 0.01 degree for the years 1800-2100.
//! Atmospheric refraction is **not** applied: the altitude is the true
//! (geometric) one, as daylight simulation programs use it.
//!
//! Scene axes: `+z` is up, `+y` north and `+x` east; the azimuth is
//! measured from north towards east (clockwise seen from above).

use glam::DVec3;

/// The sun's altitude and azimuth \[deg\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolarPosition {
    /// Altitude above the horizon \[deg\] (negative below it), no refraction.
    pub altitude: f64,
    /// Azimuth from north towards east \[deg\], in `[0, 360)`.
    pub azimuth: f64,
    /// Declination \[deg\].
    pub declination: f64,
    /// Equation of time: apparent minus mean solar time \[min\].
    pub equation_of_time: f64,
}

/// A date and time of day in Coordinated Universal Time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UtcTime {
    /// Gregorian year.
    pub year: i32,
    /// Month, 1-12.
    pub month: u32,
    /// Day of the month, 1-31.
    pub day: u32,
    /// Hours since midnight UTC \[h\], fractional.
    pub hour: f64,
}

impl UtcTime {
    /// The Julian day (Meeus, eq. 7.1, Gregorian calendar).
    pub fn julian_day(&self) -> f64 {
        let (mut y, mut m) = (self.year as f64, self.month as f64);
        if self.month <= 2 {
            y -= 1.0;
            m += 12.0;
        }
        let a = (y / 100.0).floor();
        let b = 2.0 - a + (a / 4.0).floor();
        (365.25 * (y + 4716.0)).floor() + (30.6001 * (m + 1.0)).floor() + self.day as f64 + b
            - 1524.5
            + self.hour / 24.0
    }
}

/// The sun's position for a time (UTC) and a place: `latitude` [deg, north
/// positive] and `longitude` [deg, east positive].
pub fn solar_position(t: &UtcTime, latitude: f64, longitude: f64) -> SolarPosition {
    let rad = f64::to_radians;
    // Julian centuries since J2000.0.
    let jc = (t.julian_day() - 2_451_545.0) / 36_525.0;
    let l0 = (280.466_46 + jc * (36_000.769_83 + jc * 0.000_303_2)).rem_euclid(360.0);
    let m = 357.529_11 + jc * (35_999.050_29 - 0.000_153_7 * jc);
    let e = 0.016_708_634 - jc * (0.000_042_037 + 0.000_000_126_7 * jc);
    let centre = rad(m).sin() * (1.914_602 - jc * (0.004_817 + 0.000_014 * jc))
        + rad(2.0 * m).sin() * (0.019_993 - 0.000_101 * jc)
        + rad(3.0 * m).sin() * 0.000_289;
    let true_long = l0 + centre;
    let omega = 125.04 - 1934.136 * jc;
    let apparent = true_long - 0.005_69 - 0.004_78 * rad(omega).sin();
    let eps0 =
        23.0 + (26.0 + (21.448 - jc * (46.815 + jc * (0.000_59 - jc * 0.001_813))) / 60.0) / 60.0;
    let eps = eps0 + 0.002_56 * rad(omega).cos();
    let decl = (rad(eps).sin() * rad(apparent).sin()).asin();
    // Equation of time [min] (Meeus 28.3, in the NOAA form).
    let y = (rad(eps) / 2.0).tan().powi(2);
    let eot = 4.0
        * (y * (2.0 * rad(l0)).sin() - 2.0 * e * rad(m).sin()
            + 4.0 * e * y * rad(m).sin() * (2.0 * rad(l0)).cos()
            - 0.5 * y * y * (4.0 * rad(l0)).sin()
            - 1.25 * e * e * (2.0 * rad(m)).sin())
        .to_degrees();
    // True solar time [min] and hour angle [deg] (0 at solar noon, positive
    // in the afternoon).
    let tst = (t.hour * 60.0 + eot + 4.0 * longitude).rem_euclid(1440.0);
    let hour_angle = tst / 4.0 - 180.0;
    let (phi, h) = (rad(latitude), rad(hour_angle));
    let sin_alt = phi.sin() * decl.sin() + phi.cos() * decl.cos() * h.cos();
    let altitude = sin_alt.clamp(-1.0, 1.0).asin();
    // Azimuth from north towards east: the sun's horizontal direction has
    // east component -cos(decl) sin(H) and north component
    // sin(decl) cos(phi) - cos(decl) sin(phi) cos(H).
    let east = -decl.cos() * h.sin();
    let north = decl.sin() * phi.cos() - decl.cos() * phi.sin() * h.cos();
    let azimuth = east.atan2(north).to_degrees().rem_euclid(360.0);
    SolarPosition {
        altitude: altitude.to_degrees(),
        azimuth,
        declination: decl.to_degrees(),
        equation_of_time: eot,
    }
}

/// Unit vector towards the sun from its altitude and azimuth \[deg\] (scene
/// axes: `+z` up, `+y` north, `+x` east).
pub fn sun_direction(altitude: f64, azimuth: f64) -> DVec3 {
    let (sa, ca) = altitude.to_radians().sin_cos();
    let (sz, cz) = azimuth.to_radians().sin_cos();
    DVec3::new(ca * sz, ca * cz, sa)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Astronomical Almanac's low-precision formulae (a second,
    /// independent algorithm: mean longitude and anomaly, right ascension
    /// and sidereal time), good to about 0.01 degree for 1950-2050.
    fn almanac(t: &UtcTime, lat: f64, lon: f64) -> (f64, f64) {
        let rad = f64::to_radians;
        let n = t.julian_day() - 2_451_545.0;
        let l = (280.460 + 0.985_647_4 * n).rem_euclid(360.0);
        let g = rad((357.528 + 0.985_600_3 * n).rem_euclid(360.0));
        let lambda = rad(l + 1.915 * g.sin() + 0.020 * (2.0 * g).sin());
        let eps = rad(23.439 - 0.000_000_4 * n);
        let ra = (eps.cos() * lambda.sin()).atan2(lambda.cos());
        let decl = (eps.sin() * lambda.sin()).asin();
        // Greenwich mean sidereal time [h] (the USNO approximation).
        let gmst = (18.697_374_558 + 24.065_709_824_419_08 * n).rem_euclid(24.0);
        let ha = rad(gmst * 15.0 + lon) - ra;
        let phi = rad(lat);
        let alt = (phi.sin() * decl.sin() + phi.cos() * decl.cos() * ha.cos()).asin();
        let east = -decl.cos() * ha.sin();
        let north = decl.sin() * phi.cos() - decl.cos() * phi.sin() * ha.cos();
        (
            alt.to_degrees(),
            east.atan2(north).to_degrees().rem_euclid(360.0),
        )
    }

    #[test]
    fn julian_day_of_known_dates() {
        // Meeus, example 7.a and the J2000.0 epoch.
        let t = UtcTime {
            year: 1957,
            month: 10,
            day: 4,
            hour: 0.81 * 24.0,
        };
        assert!((t.julian_day() - 2_436_116.31).abs() < 1e-6);
        let t = UtcTime {
            year: 2000,
            month: 1,
            day: 1,
            hour: 12.0,
        };
        assert_eq!(t.julian_day(), 2_451_545.0);
    }

    #[test]
    fn agrees_with_the_almanac_algorithm_over_years_and_places() {
        let mut worst: f64 = 0.0;
        for year in [1960, 1995, 2026, 2049] {
            for month in 1..=12 {
                for (lat, lon) in [(52.5, 13.4), (-33.9, 18.4), (0.0, -78.5), (64.1, -21.9)] {
                    for hour in [6.5, 9.0, 12.25, 15.0, 18.75] {
                        let t = UtcTime {
                            year,
                            month,
                            day: 15,
                            hour,
                        };
                        let s = solar_position(&t, lat, lon);
                        let (alt, az) = almanac(&t, lat, lon);
                        worst = worst.max((s.altitude - alt).abs());
                        assert!(
                            (s.altitude - alt).abs() < 0.03,
                            "{t:?} {lat}: {} vs {alt}",
                            s.altitude
                        );
                        // The azimuth is ill-defined near the zenith.
                        if alt < 85.0 {
                            let daz = (s.azimuth - az + 540.0).rem_euclid(360.0) - 180.0;
                            assert!(daz.abs() < 0.05, "{t:?} {lat}: {} vs {az}", s.azimuth);
                        }
                    }
                }
            }
        }
        assert!(worst > 0.0);
    }

    #[test]
    fn solstices_equinoxes_and_the_equation_of_time() {
        let at = |month, day, hour| UtcTime {
            year: 2026,
            month,
            day,
            hour,
        };
        // Declination at the solstices: +-23.44 degrees.
        let s = solar_position(&at(6, 21, 8.4), 0.0, 0.0);
        assert!((s.declination - 23.44).abs() < 0.01, "{}", s.declination);
        let s = solar_position(&at(12, 21, 15.0), 0.0, 0.0);
        assert!((s.declination + 23.44).abs() < 0.01, "{}", s.declination);
        // March equinox 2026: 20 March, 14:46 UTC.
        let s = solar_position(&at(3, 20, 14.77), 0.0, 0.0);
        assert!(s.declination.abs() < 0.005, "{}", s.declination);
        // Equation of time: about -14.2 min in mid-February, +16.4 min early
        // in November.
        let s = solar_position(&at(2, 11, 12.0), 0.0, 0.0);
        assert!(
            (s.equation_of_time + 14.2).abs() < 0.2,
            "{}",
            s.equation_of_time
        );
        let s = solar_position(&at(11, 3, 12.0), 0.0, 0.0);
        assert!(
            (s.equation_of_time - 16.4).abs() < 0.2,
            "{}",
            s.equation_of_time
        );
        // At solar noon the sun is due south (north of the tropics), at
        // altitude 90 - latitude + declination.
        let s0 = solar_position(&at(6, 21, 12.0), 52.0, 0.0);
        let noon = 12.0 - s0.equation_of_time / 60.0;
        let s = solar_position(&at(6, 21, noon), 52.0, 0.0);
        assert!((s.azimuth - 180.0).abs() < 0.05, "{}", s.azimuth);
        assert!((s.altitude - (38.0 + s.declination)).abs() < 1e-3);
        // Morning sun in the east, afternoon sun in the west, the midnight
        // sun below the horizon at 52 degrees north.
        let am = solar_position(&at(6, 21, 6.0), 52.0, 0.0);
        assert!(
            am.azimuth > 45.0 && am.azimuth < 100.0 && am.altitude > 5.0,
            "{am:?}"
        );
        let pm = solar_position(&at(6, 21, 18.0), 52.0, 0.0);
        assert!(
            pm.azimuth > 260.0 && pm.azimuth < 315.0 && pm.altitude > 5.0,
            "{pm:?}"
        );
        let night = solar_position(&at(6, 21, 0.0), 52.0, 0.0);
        let north = night.azimuth < 1.0 || night.azimuth > 359.0;
        assert!(night.altitude < -10.0 && north, "{night:?}");
        // Southern hemisphere: the noon sun is due north.
        let s = solar_position(&at(6, 21, noon), -34.0, 0.0);
        assert!(s.azimuth < 0.05 || s.azimuth > 359.95, "{s:?}");
    }

    #[test]
    fn direction_axes() {
        assert!((sun_direction(90.0, 0.0) - DVec3::Z).length() < 1e-15);
        assert!((sun_direction(0.0, 0.0) - DVec3::Y).length() < 1e-15);
        assert!((sun_direction(0.0, 90.0) - DVec3::X).length() < 1e-15);
        assert!(
            (sun_direction(30.0, 180.0) - DVec3::new(0.0, -0.75f64.sqrt(), 0.5)).length() < 1e-15
        );
    }
}
