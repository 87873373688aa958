//! The range checks of a model: every numeric parameter against its stated range, each
//! error naming the file, the dotted key and what is allowed.

use super::{
    Model, ModelError, RailEnds, RigidRegion, StartKind, WebShape, DEFAULT_RIM_INNER_RADIUS_M,
    MIN_RIM_THICKNESS_M, MIN_WEB_HEIGHT_M, WEB_RIM_CLEARANCE_M,
};
use crate::mesh::wheel::WheelParams;

impl Model {
    /// Checks every value against its allowed range; `file` names the source in the error.
    /// One check per TOML section, in the order of the file; the first error is returned.
    pub fn validate(&self, file: &str) -> Result<(), ModelError> {
        let mut c = Checker { file };
        self.validate_track(&mut c)?;
        self.validate_rail(&mut c)?;
        self.validate_sleeper(&mut c)?;
        self.validate_fastening(&mut c)?;
        self.validate_ballast(&mut c)?;
        self.validate_wheel(&mut c)?;
        self.validate_vehicle(&mut c)?;
        self.validate_contact(&mut c)?;
        self.validate_mesh(&mut c)?;
        self.validate_run(&mut c)?;
        self.validate_wear(&mut c)?;
        self.validate_explicit(&mut c)?;
        self.validate_start(&mut c)?;
        let run = &self.run;
        let room = self.track_length() - run.solution_zone_offset;
        // The wear analysis band-passes the zone's record to 20-80 mm: it must hold the
        // band's longest wavelength.
        let shortest = crate::spectral::BandPass::default().lambda_max_m;
        c.range(
            "run.solution_zone_length",
            run.solution_zone_length,
            shortest,
            room,
            "m (at least the analysis band's longest wavelength, which the zone's record must hold; the zone must fit on the track after run.solution_zone_offset)",
        )?;
        self.validate_ends(&mut c)?;
        Ok(())
    }

    /// `[track]`: bays and sleeper spacing.
    fn validate_track(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        let t = &self.track;
        c.int("track.bays", t.bays, 2, 400)?;
        c.range("track.sleeper_spacing", t.sleeper_spacing, 0.2, 2.0, "m")?;
        c.range(
            "track.absorbing_layer_length",
            t.absorbing_layer_length,
            0.0,
            10.0,
            "m",
        )?;
        c.range(
            "track.absorbing_layer_rate",
            t.absorbing_layer_rate,
            0.0,
            1e6,
            "1/s",
        )?;
        Ok(())
    }

    /// With absorbing rail ends: each end's absorbing layer lies outside the wheel's travel
    /// (from its start to the solution zone's end, the zone centred on the track).
    fn validate_ends(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        let t = &self.track;
        if t.ends != RailEnds::Absorbing {
            return Ok(());
        }
        let length = self.track_length();
        let zone_start = 0.5 * (length - self.run.solution_zone_length);
        let wheel_start = (zone_start - self.run.solution_zone_offset).max(0.0);
        let room = wheel_start.min(length - zone_start - self.run.solution_zone_length);
        if t.absorbing_layer_length > room {
            return c.fail(
                "track.absorbing_layer_length",
                t.absorbing_layer_length.to_string(),
                format!(
                    "0 to {room:.3} m on this track: the layer at each end must lie outside the wheel's travel ({wheel_start:.3} to {:.3} m of a {length:.3} m track); lengthen the track (track.bays) or shorten the layer or run.solution_zone_offset",
                    zone_start + self.run.solution_zone_length
                ),
            );
        }
        Ok(())
    }

    /// `[rail]`: profile, inclination and material.
    fn validate_rail(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        let r = &self.rail;
        if r.profile != "uic54" {
            return Err(ModelError::OutOfRange {
                file: c.file.into(),
                key: "rail.profile".into(),
                value: format!("{:?}", r.profile),
                allowed: "\"uic54\"".into(),
            });
        }
        c.range(
            "rail.inclination",
            r.inclination,
            0.0,
            0.1,
            "(tan of cant angle)",
        )?;
        c.elastic("rail", r.youngs_modulus, r.poisson_ratio, r.density)?;
        Ok(())
    }

    /// `[sleeper]`: dimensions (the width within the sleeper spacing, the rail seat inside
    /// the sleeper) and material.
    fn validate_sleeper(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        let t = &self.track;
        let s = &self.sleeper;
        c.range("sleeper.length", s.length, 0.3, 5.0, "m")?;
        c.range(
            "sleeper.width",
            s.width,
            0.05,
            t.sleeper_spacing,
            "m (at most the sleeper spacing)",
        )?;
        c.range("sleeper.height", s.height, 0.05, 1.0, "m")?;
        c.range(
            "sleeper.rail_seat",
            s.rail_seat,
            0.1,
            s.length - 0.1,
            "m (inside the sleeper)",
        )?;
        c.elastic("sleeper", s.youngs_modulus, s.poisson_ratio, s.density)?;
        Ok(())
    }

    /// `[fastening]`: the grid of the footprint, the pad, the springs and dampers, the holds,
    /// and a railpad spring in every direction without a rigid hold.
    fn validate_fastening(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        let s = &self.sleeper;
        let f = &self.fastening;
        c.int("fastening.rows", f.rows, 1, 16)?;
        c.int("fastening.columns", f.columns, 1, 16)?;
        c.pos(
            "fastening.footprint_length",
            f.footprint_length,
            s.width,
            "m (within the sleeper width)",
        )?;
        c.pos(
            "fastening.footprint_width",
            f.footprint_width,
            crate::mesh::profile::UIC54_FOOT_WIDTH_M,
            "m (within the 0.14 m foot of the UIC54 rail)",
        )?;
        let max_strip =
            (f.footprint_length / f.columns as f64).min(f.footprint_width / f.rows as f64);
        c.pos(
            "fastening.strip_width",
            f.strip_width,
            max_strip,
            "m (at most one grid cell)",
        )?;
        c.range("fastening.pad_thickness", f.pad_thickness, 0.0, 0.05, "m")?;
        c.spring_damper("fastening", f.springs.stiffness(), f.springs.damping())?;
        f.validate_holds(c.file)?;
        // The rail floats on the railpads where no rigid hold acts: a direction without a hold
        // needs a railpad spring, else the rail is a free body in it.
        let pattern = self.fastening.hold_pattern();
        for (h, key, k) in [
            (
                &pattern.x,
                "fastening.longitudinal_stiffness",
                f.springs.longitudinal_stiffness,
            ),
            (
                &pattern.y,
                "fastening.lateral_stiffness",
                f.springs.lateral_stiffness,
            ),
            (
                &pattern.z,
                "fastening.vertical_stiffness",
                f.springs.vertical_stiffness,
            ),
        ] {
            if h.region() == RigidRegion::None {
                c.pos(
                    key,
                    k,
                    1e12,
                    "N/m (> 0: this direction has no rigid hold in the fastening model, so the railpad springs alone support the rail)",
                )?;
            }
        }
        Ok(())
    }

    /// `[ballast]`: springs and dampers, a spring in every direction.
    fn validate_ballast(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        let b = &self.ballast;
        c.spring_damper("ballast", b.stiffness(), b.damping())?;
        // Sleepers float on the ballast: they need a spring in every direction.
        for (k, v) in [
            ("vertical_stiffness", b.vertical_stiffness),
            ("lateral_stiffness", b.lateral_stiffness),
            ("longitudinal_stiffness", b.longitudinal_stiffness),
        ] {
            c.pos(
                &format!("ballast.{k}"),
                v,
                1e12,
                "N/m (> 0: a sleeper needs support in every direction)",
            )?;
        }
        Ok(())
    }

    /// `[wheel]`: radius, conicity, material and damping ratio.
    fn validate_wheel(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        let w = &self.wheel;
        c.range("wheel.radius", w.radius, 0.2, 0.8, "m")?;
        // The wheel mesh needs |c| < 0.2 (the tread must stay above the rim); treads are 1/40
        // to 1/20, so the model stops well inside.
        c.range("wheel.conicity", w.conicity, 0.0, 0.1, "(-)")?;
        c.elastic("wheel", w.youngs_modulus, w.poisson_ratio, w.density)?;
        c.range("wheel.damping_ratio", w.damping_ratio, 0.0, 0.1, "(-)")?;
        self.validate_wheel_geometry(c)
    }

    /// `[wheel]` geometry keys: each in its range, then the combinations the wheel mesh needs
    /// (a rim thick enough for the contact zone over a web of some height, the web's faces
    /// within the hub and inside the rim's faces at the hub and at the rim), so that a wheel
    /// that cannot be meshed is refused here, naming a key the file set.
    fn validate_wheel_geometry(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        let w = &self.wheel;
        let d = WheelParams::default();
        let gap = WEB_RIM_CLEARANCE_M;
        // Rim thickness: the radial room between the hub and the tread.
        let max_rim = w.radius - d.hub_radius_m - MIN_WEB_HEIGHT_M;
        let room = format!(
            "(at least {MIN_RIM_THICKNESS_M} m, the tread's fine contact zone; at most wheel.radius - {} m, so that the web stands {MIN_WEB_HEIGHT_M} m above the {} m hub)",
            d.hub_radius_m + MIN_WEB_HEIGHT_M,
            d.hub_radius_m
        );
        match w.rim_thickness {
            Some(t) if max_rim < MIN_RIM_THICKNESS_M => {
                return c.fail(
                    "wheel.radius",
                    w.radius.to_string(),
                    format!(
                        "at least {} m with wheel.rim_thickness = {t} m set {room}",
                        d.hub_radius_m + MIN_WEB_HEIGHT_M + MIN_RIM_THICKNESS_M
                    ),
                )
            }
            Some(t) => c.range(
                "wheel.rim_thickness",
                t,
                MIN_RIM_THICKNESS_M,
                max_rim,
                &format!("m {room}"),
            )?,
            None => {
                let lo = DEFAULT_RIM_INNER_RADIUS_M + MIN_RIM_THICKNESS_M;
                if w.radius < lo {
                    return c.fail(
                        "wheel.radius",
                        w.radius.to_string(),
                        format!(
                            "{} to 0.8 m with the default rim (inner radius {DEFAULT_RIM_INNER_RADIUS_M} m, at least {MIN_RIM_THICKNESS_M} m thick); set wheel.rim_thickness for a smaller wheel",
                            num(lo)
                        ),
                    );
                }
            }
        }
        if let Some(width) = w.rim_width {
            c.range(
                "wheel.rim_width",
                width,
                0.11,
                0.2,
                "m (the rim's back face is 0.07 m from the rolling circle; its field-side face at least 0.04 m beyond it, past the tread's fine contact zone)",
            )?;
        }
        let [ra, rb] = w.rim_y_m();
        let [y0, y1] = w.web_y_m();
        let (t, mid) = (y1 - y0, 0.5 * (y0 + y1));
        if let Some(t) = w.web_thickness {
            c.range(
                "wheel.web_thickness",
                t,
                0.01,
                (0.1f64).min(rb - ra - 2.0 * gap),
                &format!(
                    "m (at most 0.1 m and the rim's width {:.3} m less 2 x {gap} m)",
                    rb - ra
                ),
            )?;
        }
        if let Some(o) = w.web_offset {
            c.range("wheel.web_offset", o, -0.1, 0.1, "m")?;
        }
        if let Some(b) = w.web_bend {
            if w.web_shape == WebShape::Straight {
                return c.fail(
                    "wheel.web_bend",
                    b.to_string(),
                    "only with wheel.web_shape = \"curved\" (this web is straight)".into(),
                );
            }
            if b == 0.0 {
                return c.fail(
                    "wheel.web_bend",
                    b.to_string(),
                    "-0.1 to 0.1 m, not 0 (a curved web without a bend is the straight one: web_shape = \"straight\")".into(),
                );
            }
            c.range("wheel.web_bend", b, -0.1, 0.1, "m")?;
        }
        // The web's faces at the hub: within the hub and inside the rim's faces (the mesh
        // joins the web to the rim's y lines); at the rim, shifted by the bend, inside them.
        let (lo, hi) = (d.hub_y_m[0].max(ra + gap), d.hub_y_m[1].min(rb - gap));
        let why = format!(
            "(the web's faces within the hub, y {} to {} m, and at least {gap} m inside the rim's faces, y {} to {} m)",
            d.hub_y_m[0],
            d.hub_y_m[1],
            num(ra),
            num(rb)
        );
        if mid - 0.5 * t < lo || mid + 0.5 * t > hi {
            let half_room = (mid - lo).min(hi - mid);
            return if w.web_offset.is_some() || w.web_thickness.is_none() {
                c.fail(
                    "wheel.web_offset",
                    mid.to_string(),
                    format!(
                        "{} to {} m with a web {} m thick {why}",
                        num(lo + 0.5 * t),
                        num(hi - 0.5 * t),
                        num(t)
                    ),
                )
            } else {
                c.fail(
                    "wheel.web_thickness",
                    t.to_string(),
                    format!(
                        "0.01 to {} m with the web's mid-plane at y = {} m {why}",
                        num(2.0 * half_room),
                        num(mid)
                    ),
                )
            };
        }
        let bend = w.web_bend_m();
        let (blo, bhi) = (ra + gap + 0.5 * t - mid, rb - gap - 0.5 * t - mid);
        if bend < blo || bend > bhi {
            return c.fail(
                "wheel.web_bend",
                format!("{bend}{}", if w.web_bend.is_none() { " (the default)" } else { "" }),
                format!(
                    "{blo:.4} to {bhi:.4} m, not 0, with the web's mid-plane at the hub at y = {mid} m and {t} m thick (its faces at the rim at least {gap} m inside the rim's faces, y {ra} to {rb} m)"
                ),
            );
        }
        Ok(())
    }

    /// `[vehicle]`: wheel load, primary suspension and gravity.
    fn validate_vehicle(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        let v = &self.vehicle;
        c.pos("vehicle.wheel_load", v.wheel_load, MAX_WHEEL_LOAD_N, "N")?;
        c.range(
            "vehicle.primary_stiffness",
            v.primary_stiffness,
            MIN_PRIMARY_STIFFNESS,
            1e10,
            "N/m (primary suspensions are 1e5 to 1e7 N/m; far below, the wheel hangs free and its static flexibility swamps the elastic one)",
        )?;
        c.range(
            "vehicle.primary_damping",
            v.primary_damping,
            0.0,
            1e9,
            "N s/m",
        )?;
        // The sprung mass is wheel_load / gravity: near 0 it runs away (0 gives an infinite
        // mass). Earth's surface: 9.78 to 9.83.
        c.range("vehicle.gravity", v.gravity, 9.0, 10.5, "m/s^2")?;
        Ok(())
    }

    /// `[contact]`: friction, traction, crown radius and the contact grid (its work bounded).
    fn validate_contact(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        let k = &self.contact;
        c.pos(
            "contact.friction",
            k.friction,
            2.0,
            "(-) (> 0: the driving torque is transmitted by friction)",
        )?;
        c.range(
            "contact.traction_coefficient",
            k.traction_coefficient,
            0.0,
            k.friction,
            "(-) (below contact.friction)",
        )?;
        c.range(
            "contact.rail_crown_radius",
            k.rail_crown_radius,
            0.05,
            10.0,
            "m",
        )?;
        c.int("contact.grid_nx", k.grid_nx, 8, 256)?;
        c.int("contact.grid_ny", k.grid_ny, 4, 256)?;
        // A passage's contact work grows as grid_nx² · grid_ny (grid_nx cells per step and
        // steps of one cell): refuse grids far beyond the default's time.
        let work = k.grid_nx * k.grid_nx * k.grid_ny;
        if work > MAX_GRID_WORK {
            return c.fail(
                "contact.grid_nx",
                format!("{} (with contact.grid_ny = {})", k.grid_nx, k.grid_ny),
                format!(
                    "grid_nx^2 * grid_ny at most {MAX_GRID_WORK} (here {work}: {:.0} times the 32 x 24 default's passage time; e.g. 64 x 64 is {:.1} times)",
                    work as f64 / (32.0 * 32.0 * 24.0),
                    64.0 * 64.0 * 64.0 / (32.0 * 32.0 * 24.0)
                ),
            );
        }
        c.range("contact.grid_margin", k.grid_margin, 1.05, 3.0, "(-)")?;
        // The fe-patch's split takes the global mesh's share of the local compliance off the
        // contact; that share is in the residual flexibilities (docs/theory.md §6.9).
        if k.influence == super::ContactInfluence::FePatch {
            for (key, on) in [
                ("run.residual_flexibility", self.run.residual_flexibility),
                (
                    "run.wheel_residual_flexibility",
                    self.run.wheel_residual_flexibility,
                ),
            ] {
                if !on {
                    return c.fail(
                        key,
                        "false".to_string(),
                        "true with contact.influence = \"fe-patch\" (its split takes the global mesh's share of the local contact compliance off the contact, and that share is in the residual flexibility)".to_string(),
                    );
                }
            }
        }
        Ok(())
    }

    /// `[mesh]`: element sizes of the track, the section, the sleepers and the wheel.
    fn validate_mesh(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        let t = &self.track;
        let m = &self.mesh;
        c.pos(
            "mesh.element_length",
            m.element_length,
            t.sleeper_spacing / 4.0,
            "m (at most a quarter of the sleeper spacing)",
        )?;
        c.pos(
            "mesh.fine_element_length",
            m.fine_element_length,
            m.element_length,
            "m (at most mesh.element_length)",
        )?;
        c.range("mesh.section_size", m.section_size, 0.002, 0.05, "m")?;
        c.range(
            "mesh.head_size",
            m.head_size,
            0.001,
            m.section_size,
            "m (at most mesh.section_size)",
        )?;
        for (i, n) in m.sleeper_elements.iter().enumerate() {
            c.int(&format!("mesh.sleeper_elements[{i}]"), *n, 1, 64)?;
        }
        c.int("mesh.wheel_segments", m.wheel_segments, 12, 720)?;
        c.range(
            "mesh.wheel_element_size",
            m.wheel_element_size,
            0.005,
            0.1,
            "m",
        )?;
        Ok(())
    }

    /// `[run]`: speed, solution-zone offset and frequency limit (the zone length is checked
    /// last, against the track length).
    fn validate_run(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        let run = &self.run;
        c.range(
            "run.speed_kmh",
            run.speed_kmh,
            SPEED_KMH[0],
            SPEED_KMH[1],
            SPEED_KMH_WHY,
        )?;
        c.range(
            "run.solution_zone_offset",
            run.solution_zone_offset,
            0.0,
            10.0,
            "m",
        )?;
        c.range("run.fmax", run.fmax, FMAX_HZ[0], FMAX_HZ[1], "Hz")?;
        Ok(())
    }

    /// `[wear]`: coefficient and initiation threshold.
    fn validate_wear(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        c.pos("wear.coefficient", self.wear.coefficient, 1e-6, "m^3/J")?;
        c.range(
            "wear.initiation_threshold",
            self.wear.initiation_threshold,
            0.0,
            1.0,
            "-",
        )?;
        Ok(())
    }

    /// `[explicit]`: safety factor and the time step's physical range.
    fn validate_explicit(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        c.range("explicit.safety", self.explicit.safety, 0.1, 1.0, "-")?;
        if let Some(dt) = self.explicit.time_step {
            // The stable limit depends on the assembled matrices and is checked when the
            // explicit model is built; here only a physical range.
            c.range("explicit.time_step", dt, 1e-10, 1e-4, "s")?;
        }
        Ok(())
    }
}

impl Model {
    /// The start of a passage: `run.rest_start_distance` in its range, and with
    /// `run.start = "rest"` inside the run-in (the torque comes on after the wheel's start).
    fn validate_start(&self, c: &mut Checker<'_>) -> Result<(), ModelError> {
        let run = &self.run;
        c.pos(
            "run.rest_start_distance",
            run.rest_start_distance,
            10.0,
            "m (distance before the solution zone at which the driving torque comes on)",
        )?;
        if run.start == StartKind::Rest {
            let run_in = self.run_in_m();
            if run.rest_start_distance > run_in + 1e-12 {
                return c.fail(
                    "run.rest_start_distance",
                    run.rest_start_distance.to_string(),
                    format!(
                        "greater than 0 and at most the run-in {run_in:.3} m with run.start = \"rest\" (the wheel starts min(run.solution_zone_offset, (track length - run.solution_zone_length)/2) before the zone; to apply the torque earlier raise run.solution_zone_offset, and track.bays if the track is too short)"
                    ),
                );
            }
        }
        Ok(())
    }

    /// The run-in (m): the distance from the wheel's start to the solution zone,
    /// `run.solution_zone_offset` unless the zone, centred on the track, leaves less room.
    pub fn run_in_m(&self) -> f64 {
        let zone_start = 0.5 * (self.track_length() - self.run.solution_zone_length);
        self.run.solution_zone_offset.min(zone_start).max(0.0)
    }
}

/// Allowed train speed (km/h), of `run.speed_kmh` and of every speed a sweep, study or
/// initiation table runs: the model is not meant beyond 500 km/h, and below 40 km/h a passage
/// does not run. The passage's time step is the contact step `Δt = Δx/V` (one contact-grid
/// element over the speed, docs/theory.md §6.5: 16 µs at 140 km/h on the default grid, 56 µs
/// at 40 km/h), and the contact force is coupled to the structures explicitly (computed from
/// the displacements the last step's force produced, §7.2), which is stable only while `Δt`
/// is short against the period of the stiffest motion coupled through the contact spring:
/// below about 30 km/h on the default model and on the small test model the normal
/// force oscillates more at every step until the contact patch leaves the contact grid, and
/// `contact.grid_margin` cannot help. 40 km/h keeps a margin above that on the shipped
/// models with either start.
pub const SPEED_KMH: [f64; 2] = [40.0, 500.0];

/// The range of `run.fmax` and of the `modes` command's upper frequency (Hz).
pub const FMAX_HZ: [f64; 2] = [100.0, 20000.0];

/// The unit of [`SPEED_KMH`] and why it starts at 40 km/h, for the range errors.
pub const SPEED_KMH_WHY: &str = "km/h (below 40 km/h the passage's contact step, one contact-grid element over the speed, is too long for the explicit coupling of the contact and the structures: the normal force grows step by step until the patch leaves the contact grid)";

/// Smallest primary suspension stiffness per wheel (N/m): a 10 t sprung mass on it bounces
/// at 0.05 Hz, far below any railway primary suspension (1e5 to 1e7 N/m, 1 to 10 Hz); the
/// wheel then loses contact at once (a passage says so), and near 1 N/m its free-body
/// flexibility swamps the elastic one in the wheel's residual-flexibility check.
pub(crate) const MIN_PRIMARY_STIFFNESS: f64 = 1e3;

/// Largest static wheel load (N): 50 t per wheel, beyond any railway axle load.
pub const MAX_WHEEL_LOAD_N: f64 = 500e3;

/// Largest `contact.grid_nx² · contact.grid_ny`: 12 times the default 32 × 24 grid's passage
/// time (64 × 64 takes 10.7 times; 256 × 256 would take 680 times, hours in place of minutes).
pub const MAX_GRID_WORK: usize = 12 * 32 * 32 * 24;

/// Allowed Young's modulus of the rail, sleeper and wheel (Pa): the solids a track is made of
/// (steel 2.1e11, concrete 3.8e10, polymers from 1e9). Far outside it the modal bases and the
/// contact grid go out of scale (e.g. E = 1e-12 Pa puts thousands of modes below `run.fmax`).
pub(crate) const YOUNGS_MODULUS_PA: [f64; 2] = [1e9, 1e13];

/// Allowed Poisson's ratio of the rail, sleeper and wheel (−). Above 0.45 a solid is nearly
/// incompressible: its dilatational wave speed, hence the explicit time step, runs away and
/// the linear hexahedra lock.
pub(crate) const POISSON_RATIO: [f64; 2] = [0.0, 0.45];

/// Allowed density of the rail, sleeper and wheel (kg/m³): steel 7800, concrete 2500.
pub(crate) const DENSITY_KG_M3: [f64; 2] = [1000.0, 20000.0];

/// A computed bound as a reader expects it: rounded to 12 significant digits and printed in
/// the shortest form (0.39 + 0.03 prints 0.42, not 0.42000000000000004).
fn num(x: f64) -> String {
    if !x.is_finite() {
        return x.to_string();
    }
    format!("{x:.11e}")
        .parse::<f64>()
        .map_or_else(|_| x.to_string(), |r| r.to_string())
}

struct Checker<'a> {
    file: &'a str,
}

impl Checker<'_> {
    fn fail(&self, key: &str, value: String, allowed: String) -> Result<(), ModelError> {
        Err(ModelError::OutOfRange {
            file: self.file.into(),
            key: key.into(),
            value,
            allowed,
        })
    }
    /// lo ≤ v ≤ hi, finite.
    fn range(&mut self, key: &str, v: f64, lo: f64, hi: f64, unit: &str) -> Result<(), ModelError> {
        if !(v.is_finite() && v >= lo && v <= hi) {
            return self.fail(
                key,
                v.to_string(),
                format!("{} to {} {unit}", num(lo), num(hi)),
            );
        }
        Ok(())
    }
    /// 0 < v ≤ hi, finite.
    fn pos(&mut self, key: &str, v: f64, hi: f64, unit: &str) -> Result<(), ModelError> {
        if !(v.is_finite() && v > 0.0 && v <= hi) {
            return self.fail(
                key,
                v.to_string(),
                format!("greater than 0 and at most {} {unit}", num(hi)),
            );
        }
        Ok(())
    }
    /// Stiffness (N/m) and damping (N·s/m) in x, y, z under `prefix`: each 0 to 1e12.
    fn spring_damper(&mut self, prefix: &str, k: [f64; 3], c: [f64; 3]) -> Result<(), ModelError> {
        for (d, name) in ["longitudinal", "lateral", "vertical"].iter().enumerate() {
            self.range(
                &format!("{prefix}.{name}_stiffness"),
                k[d],
                0.0,
                1e12,
                "N/m",
            )?;
            self.range(
                &format!("{prefix}.{name}_damping"),
                c[d],
                0.0,
                1e12,
                "N s/m",
            )?;
        }
        Ok(())
    }

    fn int(&mut self, key: &str, v: usize, lo: usize, hi: usize) -> Result<(), ModelError> {
        if v < lo || v > hi {
            return self.fail(key, v.to_string(), format!("{lo} to {hi}"));
        }
        Ok(())
    }
    /// Young's modulus, Poisson's ratio and density of a solid part in their physical ranges
    /// ([`YOUNGS_MODULUS_PA`], [`POISSON_RATIO`], [`DENSITY_KG_M3`]).
    fn elastic(&mut self, part: &str, e: f64, nu: f64, rho: f64) -> Result<(), ModelError> {
        let [e_lo, e_hi] = YOUNGS_MODULUS_PA;
        self.range(
            &format!("{part}.youngs_modulus"),
            e,
            e_lo,
            e_hi,
            "Pa (solids of a track: steel 2.1e11, concrete 3.8e10)",
        )?;
        let [nu_lo, nu_hi] = POISSON_RATIO;
        self.range(
            &format!("{part}.poisson_ratio"),
            nu,
            nu_lo,
            nu_hi,
            "(-) (nearly incompressible material is not supported)",
        )?;
        let [rho_lo, rho_hi] = DENSITY_KG_M3;
        self.range(
            &format!("{part}.density"),
            rho,
            rho_lo,
            rho_hi,
            "kg/m^3 (steel 7800, concrete 2500)",
        )
    }
}
