//! The identity of a model: the one function ([`model_identity`]) that says whether two
//! models give the same results, for the resume key of a sweep, the case hash of a study and
//! the modal cache key. A [`IdentityScope`] says what the identity covers:
//!
//! - [`IdentityScope::Run`]: every section of the model; any change makes a new run.
//! - [`IdentityScope::Modes`]: the sections that K and M read. It leaves out the contact,
//!   wear and explicit sections; the speed, the passage's `run.fmax` (keyed separately by the
//!   cache) and the residual-flexibility switches; and every damper (railpads, ballast,
//!   elastic holds, the rail ends' dashpots, primary suspension, the wheel's modal damping
//!   ratio): dampers enter C only,
//!   so a damping or speed study reuses the modes.
//! - [`IdentityScope::Track`]: `Modes` without the wheel, the vehicle and the wheel's mesh
//!   keys (the track is built without them).
//! - [`IdentityScope::Wheel`]: `Modes` restricted to the wheel, the vehicle and the wheel's
//!   mesh keys (`WheelStructure::build` reads only these).
//! - [`IdentityScope::Components`]: `Track` without any spring's stiffness (the track's
//!   component bases; the springs enter only their coupling).
//!
//! Each scope but `Run` is a typed view of the model that names the fields it holds (a new
//! field is in no modes identity until a view names it); the views give the bytes the earlier
//! key-removal code gave (tested on every model file of the repository), so every cache key
//! is unchanged.

use serde::Serialize;
use serde_json::Value;

use super::fastening::{FasteningLayout, FasteningStiffness};
use super::{
    is_true, MassKind, MeshParams, Model, NodePlanes, Rail, Run, Sleeper, SpringDampers, Track,
    Vehicle, WebShape, Wheel,
};

/// What a model identity covers (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IdentityScope {
    /// The whole model: results of a passage, a sweep or a study case.
    Run,
    /// The sections K and M of the track and the wheel read.
    Modes,
    /// The sections the track's K and M read.
    Track,
    /// The sections the wheel's K and M read.
    Wheel,
    /// `Track` without any spring's stiffness: what the track's component bases read (the
    /// springs enter their coupling, not the components; `eigen::substructure`).
    Components,
}

/// The identity of `m` in `scope`: its JSON, the bytes that are hashed. Equal models give
/// equal bytes; a change outside the scope leaves them unchanged.
pub fn model_identity(m: &Model, scope: IdentityScope) -> Result<Vec<u8>, serde_json::Error> {
    match scope {
        IdentityScope::Run => serde_json::to_vec(m),
        _ => serde_json::to_vec(&scoped_value(m, scope)?),
    }
}

/// The resume key of a run of `m` into a directory: the program version and the hash of the
/// whole model ([`IdentityScope::Run`]), `"VERSION HEX"`.
pub fn run_key(m: &Model) -> Result<String, serde_json::Error> {
    Ok(format!(
        "{} {}",
        env!("CARGO_PKG_VERSION"),
        blake3::hash(&model_identity(m, IdentityScope::Run)?).to_hex()
    ))
}

/// The model's sections in `scope` as JSON (keys sorted); for [`IdentityScope::Run`] the whole
/// model. Each scope is a typed view that names the fields it holds (`ModesView`,
/// `TrackView`, `WheelView`, `ComponentsView`); the views take their sources apart field by
/// field, so a field added to the model does not compile until a view holds or leaves it.
pub(crate) fn scoped_value(m: &Model, scope: IdentityScope) -> Result<Value, serde_json::Error> {
    match scope {
        IdentityScope::Run => serde_json::to_value(m),
        IdentityScope::Modes => serde_json::to_value(ModesView::of(m)),
        IdentityScope::Track => serde_json::to_value(TrackView::of(m)),
        IdentityScope::Wheel => serde_json::to_value(WheelView::of(m)),
        IdentityScope::Components => serde_json::to_value(ComponentsView::of(m)),
    }
}

/// What the track's component bases read: [`TrackView`] without a spring's stiffness (the
/// railpads', the ballast's, the holds'; a node line's own `line_stiffness` stays).
#[derive(Serialize)]
struct ComponentsView<'a> {
    track: TrackLayout,
    rail: &'a Rail,
    sleeper: &'a Sleeper,
    fastening: FasteningLayout,
    /// The ballast holds nothing but its springs.
    ballast: Nothing,
    mesh: TrackMesh<'a>,
    run: SolutionZone,
}

/// An empty table.
#[derive(Serialize)]
struct Nothing {}

impl<'a> ComponentsView<'a> {
    fn of(m: &'a Model) -> Self {
        ComponentsView {
            track: TrackLayout::of(&m.track),
            rail: &m.rail,
            sleeper: &m.sleeper,
            fastening: m.fastening.layout_view(),
            ballast: Nothing {},
            mesh: TrackMesh::of(&m.mesh),
            run: SolutionZone::of(&m.run),
        }
    }
}

/// What the track's and the wheel's K and M read: every structural section, without the
/// contact, wear and explicit sections, the passage settings of `run` (the solution zone
/// stays: it places the fine mesh) and every damper.
#[derive(Serialize)]
struct ModesView<'a> {
    #[serde(flatten)]
    track: TrackSections<'a>,
    wheel: WheelStiffness<'a>,
    vehicle: VehicleStiffness,
    mesh: &'a MeshParams,
}

impl<'a> ModesView<'a> {
    fn of(m: &'a Model) -> Self {
        // Every section named: the contact, wear and explicit ones are read by neither K nor M.
        let Model {
            track: _,
            rail: _,
            sleeper: _,
            fastening: _,
            ballast: _,
            wheel: _,
            vehicle: _,
            contact: _,
            mesh: _,
            run: _,
            wear: _,
            explicit: _,
        } = m;
        ModesView {
            track: TrackSections::of(m),
            wheel: WheelStiffness::of(&m.wheel),
            vehicle: VehicleStiffness::of(&m.vehicle),
            mesh: &m.mesh,
        }
    }
}

/// What the track's K and M read: [`ModesView`] without the wheel, the vehicle and the wheel's
/// mesh keys (the track is built without them).
#[derive(Serialize)]
struct TrackView<'a> {
    #[serde(flatten)]
    track: TrackSections<'a>,
    mesh: TrackMesh<'a>,
}

impl<'a> TrackView<'a> {
    fn of(m: &'a Model) -> Self {
        TrackView {
            track: TrackSections::of(m),
            mesh: TrackMesh::of(&m.mesh),
        }
    }
}

/// The track's sections but the mesh, as K and M read them (in [`ModesView`] and
/// [`TrackView`]).
#[derive(Serialize)]
struct TrackSections<'a> {
    track: TrackLayout,
    rail: &'a Rail,
    sleeper: &'a Sleeper,
    fastening: FasteningStiffness,
    ballast: Stiffnesses,
    run: SolutionZone,
}

impl<'a> TrackSections<'a> {
    fn of(m: &'a Model) -> Self {
        TrackSections {
            track: TrackLayout::of(&m.track),
            rail: &m.rail,
            sleeper: &m.sleeper,
            fastening: m.fastening.stiffness_view(),
            ballast: Stiffnesses::of(&m.ballast),
            run: SolutionZone::of(&m.run),
        }
    }
}

/// What the wheel's K and M read (`WheelStructure::build`): the wheel, the vehicle and the
/// wheel's mesh keys, without the dampers.
#[derive(Serialize)]
struct WheelView<'a> {
    wheel: WheelStiffness<'a>,
    vehicle: VehicleStiffness,
    mesh: WheelMesh<'a>,
}

impl<'a> WheelView<'a> {
    fn of(m: &'a Model) -> Self {
        WheelView {
            wheel: WheelStiffness::of(&m.wheel),
            vehicle: VehicleStiffness::of(&m.vehicle),
            mesh: WheelMesh::of(&m.mesh),
        }
    }
}

/// `[track]` without the rail ends' dashpots and their layer (they enter C only).
#[derive(Serialize)]
struct TrackLayout {
    bays: usize,
    sleeper_spacing: f64,
}

impl TrackLayout {
    fn of(t: &Track) -> Self {
        // Every field named, so that a new one does not compile until it is placed.
        let Track {
            bays,
            sleeper_spacing,
            ends: _,
            absorbing_layer_length: _,
            absorbing_layer_rate: _,
        } = t;
        TrackLayout {
            bays: *bays,
            sleeper_spacing: *sleeper_spacing,
        }
    }
}

/// A spring-damper set's stiffnesses (N/m).
#[derive(Serialize)]
struct Stiffnesses {
    vertical_stiffness: f64,
    lateral_stiffness: f64,
    longitudinal_stiffness: f64,
}

impl Stiffnesses {
    fn of(s: &SpringDampers) -> Self {
        let SpringDampers {
            vertical_stiffness,
            vertical_damping: _,
            lateral_stiffness,
            lateral_damping: _,
            longitudinal_stiffness,
            longitudinal_damping: _,
        } = s;
        Stiffnesses {
            vertical_stiffness: *vertical_stiffness,
            lateral_stiffness: *lateral_stiffness,
            longitudinal_stiffness: *longitudinal_stiffness,
        }
    }
}

/// `[wheel]` without its modal damping ratio (applied after the modes).
#[derive(Serialize)]
struct WheelStiffness<'a> {
    radius: f64,
    conicity: f64,
    youngs_modulus: f64,
    poisson_ratio: f64,
    density: f64,
    #[serde(skip_serializing_if = "WebShape::is_straight")]
    web_shape: &'a WebShape,
    #[serde(skip_serializing_if = "Option::is_none")]
    web_bend: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    web_thickness: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    web_offset: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    rim_width: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    rim_thickness: Option<f64>,
    #[serde(skip_serializing_if = "is_true")]
    brake_disc: bool,
}

impl<'a> WheelStiffness<'a> {
    fn of(w: &'a Wheel) -> Self {
        let Wheel {
            radius,
            conicity,
            youngs_modulus,
            poisson_ratio,
            density,
            damping_ratio: _,
            web_shape,
            web_bend,
            web_thickness,
            web_offset,
            rim_width,
            rim_thickness,
            brake_disc,
        } = w;
        WheelStiffness {
            radius: *radius,
            conicity: *conicity,
            youngs_modulus: *youngs_modulus,
            poisson_ratio: *poisson_ratio,
            density: *density,
            web_shape,
            web_bend: *web_bend,
            web_thickness: *web_thickness,
            web_offset: *web_offset,
            rim_width: *rim_width,
            rim_thickness: *rim_thickness,
            brake_disc: *brake_disc,
        }
    }
}

/// `[vehicle]` without the primary suspension's damper.
#[derive(Serialize)]
struct VehicleStiffness {
    wheel_load: f64,
    primary_stiffness: f64,
    gravity: f64,
}

impl VehicleStiffness {
    fn of(v: &Vehicle) -> Self {
        let Vehicle {
            wheel_load,
            primary_stiffness,
            primary_damping: _,
            gravity,
        } = v;
        VehicleStiffness {
            wheel_load: *wheel_load,
            primary_stiffness: *primary_stiffness,
            gravity: *gravity,
        }
    }
}

/// `[run]`'s solution zone, which places the fine mesh.
#[derive(Serialize)]
struct SolutionZone {
    solution_zone_offset: f64,
    solution_zone_length: f64,
}

impl SolutionZone {
    fn of(r: &Run) -> Self {
        let Run {
            speed_kmh: _,
            solution_zone_offset,
            solution_zone_length,
            fmax: _,
            residual_flexibility: _,
            residual_variation: _,
            wheel_residual_flexibility: _,
            start: _,
            rest_start_distance: _,
            creepage: _,
        } = r;
        SolutionZone {
            solution_zone_offset: *solution_zone_offset,
            solution_zone_length: *solution_zone_length,
        }
    }
}

/// `[mesh]` without the wheel's keys.
#[derive(Serialize)]
struct TrackMesh<'a> {
    element_length: f64,
    fine_element_length: f64,
    section_size: f64,
    head_size: f64,
    sleeper_elements: [usize; 3],
    mass: &'a MassKind,
    #[serde(skip_serializing_if = "NodePlanes::is_graded")]
    node_planes: &'a NodePlanes,
}

impl<'a> TrackMesh<'a> {
    fn of(m: &'a MeshParams) -> Self {
        let MeshParams {
            element_length,
            fine_element_length,
            section_size,
            head_size,
            sleeper_elements,
            wheel_segments: _,
            wheel_element_size: _,
            mass,
            node_planes,
        } = m;
        TrackMesh {
            element_length: *element_length,
            fine_element_length: *fine_element_length,
            section_size: *section_size,
            head_size: *head_size,
            sleeper_elements: *sleeper_elements,
            mass,
            node_planes,
        }
    }
}

/// `[mesh]`'s wheel keys and the mass matrix kind.
#[derive(Serialize)]
struct WheelMesh<'a> {
    wheel_segments: usize,
    wheel_element_size: f64,
    mass: &'a MassKind,
}

impl<'a> WheelMesh<'a> {
    fn of(m: &'a MeshParams) -> Self {
        WheelMesh {
            wheel_segments: m.wheel_segments,
            wheel_element_size: m.wheel_element_size,
            mass: &m.mass,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{model_identity, run_key, scoped_value, IdentityScope, Model, Value};
    /// The identity as the code before the typed views computed it, kept as an independent
    /// reference: the whole model's JSON with what K and M do not read removed by key name.
    fn reference_scoped_value(m: &Model, scope: IdentityScope) -> Result<Value, serde_json::Error> {
        if scope == IdentityScope::Components {
            // the component key's removal of every spring stiffness from the track's identity
            let mut v = reference_scoped_value(m, IdentityScope::Track)?;
            if let Some(o) = v.as_object_mut() {
                for p in ["fastening", "ballast"] {
                    if let Some(f) = o.get_mut(p).and_then(|r| r.as_object_mut()) {
                        f.retain(|k, _| !k.ends_with("stiffness"));
                        if let Some(c) = f.get_mut("custom").and_then(|r| r.as_object_mut()) {
                            for h in c.values_mut() {
                                if let Some(h) = h.as_object_mut() {
                                    h.remove("stiffness");
                                }
                            }
                        }
                    }
                }
            }
            return Ok(v);
        }
        let mut v = serde_json::to_value(m)?;
        if scope == IdentityScope::Run {
            return Ok(v);
        }
        if let Some(o) = v.as_object_mut() {
            remove_non_structural(o);
            match scope {
                IdentityScope::Wheel => keep_wheel(o),
                IdentityScope::Track => drop_wheel(o),
                IdentityScope::Modes | IdentityScope::Run | IdentityScope::Components => {}
            }
        }
        Ok(v)
    }

    type Object = serde_json::Map<String, Value>;

    /// Removes what neither K nor M reads: contact, wear, explicit, the passage settings of `run`
    /// (the solution zone stays: it places the fine mesh) and every damper.
    fn remove_non_structural(o: &mut Object) {
        for k in ["contact", "wear", "explicit"] {
            o.remove(k);
        }
        if let Some(run) = o.get_mut("run").and_then(|r| r.as_object_mut()) {
            for k in [
                "speed_kmh",
                "fmax",
                "residual_flexibility",
                "residual_variation",
                "wheel_residual_flexibility",
                "start",
                "rest_start_distance",
                "creepage",
            ] {
                run.remove(k);
            }
        }
        // the rail ends' dashpots enter C only
        if let Some(t) = o.get_mut("track").and_then(|r| r.as_object_mut()) {
            for k in ["ends", "absorbing_layer_length", "absorbing_layer_rate"] {
                t.remove(k);
            }
        }
        for part in ["fastening", "ballast"] {
            if let Some(f) = o.get_mut(part).and_then(|r| r.as_object_mut()) {
                f.retain(|k, _| !k.ends_with("damping"));
                if let Some(c) = f.get_mut("custom").and_then(|r| r.as_object_mut()) {
                    for h in c.values_mut() {
                        if let Some(h) = h.as_object_mut() {
                            h.retain(|k, _| !k.ends_with("damping"));
                        }
                    }
                }
            }
        }
        if let Some(v) = o.get_mut("vehicle").and_then(|r| r.as_object_mut()) {
            v.remove("primary_damping");
        }
        if let Some(w) = o.get_mut("wheel").and_then(|r| r.as_object_mut()) {
            w.remove("damping_ratio");
        }
    }

    /// Keeps the wheel, the vehicle and the wheel's mesh keys only.
    fn keep_wheel(o: &mut Object) {
        o.retain(|k, _| matches!(k.as_str(), "wheel" | "vehicle" | "mesh"));
        if let Some(mesh) = o.get_mut("mesh").and_then(|r| r.as_object_mut()) {
            mesh.retain(|k, _| {
                matches!(k.as_str(), "wheel_segments" | "wheel_element_size" | "mass")
            });
        }
    }

    /// Removes the wheel, the vehicle and the wheel's mesh keys.
    fn drop_wheel(o: &mut Object) {
        o.remove("wheel");
        o.remove("vehicle");
        if let Some(mesh) = o.get_mut("mesh").and_then(|r| r.as_object_mut()) {
            mesh.remove("wheel_segments");
            mesh.remove("wheel_element_size");
        }
    }

    fn with(set: &[&str]) -> Model {
        let o: Vec<String> = set.iter().map(|s| s.to_string()).collect();
        crate::model::load_model(&crate::model::ModelSource::Builtin, &o).unwrap()
    }

    fn same(a: &Model, b: &Model, scope: IdentityScope) -> bool {
        model_identity(a, scope).unwrap() == model_identity(b, scope).unwrap()
    }

    const ALL: [IdentityScope; 5] = [
        IdentityScope::Run,
        IdentityScope::Modes,
        IdentityScope::Track,
        IdentityScope::Wheel,
        IdentityScope::Components,
    ];

    /// The typed views give the bytes the key-removal reference gives, on every model file of
    /// the repository and on overrides that reach every field a view names or leaves out
    /// (custom elastic and node-line holds with dampers, absorbing ends, wheel geometry,
    /// elastic preset holds, a lattice mesh, another start).
    #[test]
    fn typed_views_equal_the_key_removal_reference() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
        let mut models: Vec<(String, Model)> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .map(|p| {
                let m = crate::model::load_model(&crate::model::ModelSource::File(p.clone()), &[])
                    .unwrap();
                (p.display().to_string(), m)
            })
            .collect();
        assert!(models.len() >= 15, "{} model files", models.len());
        for set in [
            &[
                "fastening.model=custom",
                "fastening.custom.x={ elastic = \"columns\", indices = [1], stiffness = 1e9, damping = 5e3 }",
                "fastening.custom.y={ rigid = \"rows\", indices = [0, 3], node_lines = true }",
                "fastening.custom.z={ elastic = \"columns\", indices = [0, 2], node_lines = true, line_stiffness = 2e8, line_damping = 1e3 }",
            ][..],
            &["fastening.hold=elastic", "fastening.hold_stiffness=3e8", "fastening.hold_damping=2e4"],
            &["track.ends=absorbing", "track.absorbing_layer_length=0.9", "track.bays=20"],
            &[
                "wheel.web_shape=curved",
                "wheel.web_bend=0.03",
                "wheel.web_thickness=0.035",
                "wheel.web_offset=-0.02",
                "wheel.rim_width=0.14",
                "wheel.rim_thickness=0.06",
                "wheel.brake_disc=false",
                "wheel.damping_ratio=0.001",
            ],
            &["mesh.node_planes=lattice", "run.start=rest", "run.speed_kmh=120", "vehicle.primary_damping=9e3"],
        ] {
            models.push((format!("{set:?}"), with(set)));
        }
        for (name, m) in &models {
            for scope in [
                IdentityScope::Modes,
                IdentityScope::Track,
                IdentityScope::Wheel,
                IdentityScope::Components,
            ] {
                let typed = serde_json::to_vec(&scoped_value(m, scope).unwrap()).unwrap();
                let reference =
                    serde_json::to_vec(&reference_scoped_value(m, scope).unwrap()).unwrap();
                assert_eq!(
                    String::from_utf8_lossy(&typed),
                    String::from_utf8_lossy(&reference),
                    "{name}, {scope:?}"
                );
                assert_eq!(
                    model_identity(m, scope).unwrap(),
                    reference,
                    "{name}, {scope:?}"
                );
            }
        }
    }

    #[test]
    fn equal_models_have_equal_identities_in_every_scope() {
        for s in ALL {
            assert!(same(&with(&[]), &with(&[]), s), "{s:?}");
        }
        assert_eq!(run_key(&with(&[])).unwrap(), run_key(&with(&[])).unwrap());
    }

    /// The rail-end keys at their defaults are not written, so the identities (and with them
    /// the cache keys and resume keys) of models that do not set them are those of the
    /// program before the keys existed.
    #[test]
    fn default_rail_ends_leave_the_identity_as_it_was() {
        let v = serde_json::to_value(&with(&[]).track).unwrap();
        assert_eq!(v, serde_json::json!({"bays": 16, "sleeper_spacing": 0.6}));
        let v = serde_json::to_value(&with(&["track.ends=\"free\""]).track).unwrap();
        assert_eq!(v, serde_json::json!({"bays": 16, "sleeper_spacing": 0.6}));
    }

    /// The node-line keys are not written when not given: the fastening of existing models
    /// (a preset, or a custom pattern of strips) has the keys, and so the identities, it had
    /// before they existed. A line's damping leaves the modes' identity, its stiffness not.
    #[test]
    fn node_line_keys_leave_existing_identities_as_they_were() {
        let keys = |v: &Value| {
            let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
            k.sort();
            k
        };
        let v = serde_json::to_value(&with(&[]).fastening).unwrap();
        let mut want = [
            "model",
            "rows",
            "columns",
            "footprint_length",
            "footprint_width",
            "strip_width",
            "pad_thickness",
            "vertical_stiffness",
            "vertical_damping",
            "lateral_stiffness",
            "lateral_damping",
            "longitudinal_stiffness",
            "longitudinal_damping",
        ];
        want.sort();
        assert_eq!(keys(&v), want);
        let custom = |x: &str| {
            with(&[
                "fastening.model=custom",
                &format!("fastening.custom.x={x}"),
                "fastening.custom.y={ rigid = \"rows\", indices = [0, 1, 2, 3] }",
                "fastening.custom.z={ rigid = \"none\" }",
            ])
        };
        let strips =
            custom("{ elastic = \"columns\", indices = [1], stiffness = 1e9, damping = 3.0 }");
        let v = serde_json::to_value(&strips.fastening).unwrap();
        assert_eq!(
            keys(&v["custom"]["x"]),
            ["damping", "elastic", "indices", "rigid", "stiffness"]
        );
        assert_eq!(keys(&v["custom"]["y"]), ["indices", "rigid"]);
        let line = |k: f64, c: f64| {
            custom(&format!(
                "{{ elastic = \"columns\", indices = [1], node_lines = true, line_stiffness = {k:e}, line_damping = {c:e} }}"
            ))
        };
        let base = line(1e8, 0.0);
        assert!(!same(&base, &strips, IdentityScope::Track));
        for s in [IdentityScope::Modes, IdentityScope::Track] {
            assert!(same(&base, &line(1e8, 5e3), s), "{s:?}");
            assert!(!same(&base, &line(2e8, 0.0), s), "{s:?}");
        }
        assert!(!same(&base, &line(1e8, 5e3), IdentityScope::Run));
    }

    #[test]
    fn damping_and_speed_change_the_run_but_not_the_modes() {
        let base = with(&[]);
        for set in [
            &["ballast.vertical_damping=99999"][..],
            &["run.speed_kmh=61"][..],
            &["wheel.damping_ratio=0.005"][..],
            &["contact.friction=0.5"][..],
            &["run.start=rest"][..],
            &["run.rest_start_distance=0.2"][..],
            &["run.wheel_residual_flexibility=false"][..],
            &["run.creepage=increment"][..],
            &["track.ends=\"absorbing\""][..],
            &[
                "track.ends=\"absorbing\"",
                "track.absorbing_layer_length=2.0",
                "track.absorbing_layer_rate=5e3",
            ][..],
        ] {
            let m = with(set);
            assert!(!same(&base, &m, IdentityScope::Run), "{set:?}");
            assert_ne!(run_key(&base).unwrap(), run_key(&m).unwrap(), "{set:?}");
            for s in [
                IdentityScope::Modes,
                IdentityScope::Track,
                IdentityScope::Wheel,
                IdentityScope::Components,
            ] {
                assert!(same(&base, &m, s), "{set:?} {s:?}");
            }
        }
    }

    #[test]
    fn a_wheel_change_leaves_the_track_identity_and_a_rail_change_the_wheel_identity() {
        let base = with(&[]);
        let w = with(&["mesh.wheel_segments=20"]);
        assert!(!same(&base, &w, IdentityScope::Wheel));
        assert!(!same(&base, &w, IdentityScope::Run));
        assert!(same(&base, &w, IdentityScope::Track));
        let t = with(&["track.bays=5"]);
        assert!(!same(&base, &t, IdentityScope::Track));
        assert!(same(&base, &t, IdentityScope::Wheel));
    }
}

#[cfg(test)]
mod default_hash {
    use super::{model_identity, IdentityScope};
    use crate::model::load_model;
    use crate::model::ModelSource;

    /// The default model's identities in every scope, hashed: the bytes behind its modal
    /// cache keys and resume keys, as they were before the wheel's geometry keys (left out
    /// when unset) existed. Its `[wheel]` is written with the same six keys.
    #[test]
    fn the_default_models_identities_are_unchanged() {
        let m = crate::model::Model::default_model();
        for (s, hex) in [
            (
                IdentityScope::Run,
                "a2d67866409593e227ba3a12b80c1847e989e210effe560df578426f65c2ac83",
            ),
            (
                IdentityScope::Modes,
                "6317539b8bbfb5148bc41949981da7c563af4958fb97c1f8d942d6229cb4e6dd",
            ),
            (
                IdentityScope::Track,
                "3db14e25e856b80c01ec6d33d32f6ddd6461847121eac89740ee854c106b6d1e",
            ),
            (
                IdentityScope::Wheel,
                "bfef246b100aa898b373f10e96531d4ec46b73553e89d5d549521c8969b90c83",
            ),
        ] {
            let h = blake3::hash(&model_identity(&m, s).unwrap()).to_hex();
            assert_eq!(h.as_str(), hex, "{s:?}");
        }
        let v = serde_json::to_value(&m.wheel).unwrap();
        assert_eq!(
            v,
            serde_json::json!({"radius": 0.46, "conicity": 0.025, "youngs_modulus": 210e9,
                "poisson_ratio": 0.3, "density": 7800.0, "damping_ratio": 0.0})
        );
    }

    /// A wheel geometry key changes the wheel's identity (its modal cache entry) and leaves
    /// the track's.
    #[test]
    fn a_wheel_geometry_key_changes_the_wheel_identity_only() {
        let base = crate::model::Model::default_model();
        for set in [
            "wheel.web_thickness=0.035",
            "wheel.web_offset=-0.02",
            "wheel.web_shape=\"curved\"",
            "wheel.rim_width=0.14",
            "wheel.rim_thickness=0.06",
            "wheel.brake_disc=false",
        ] {
            let m = load_model(&ModelSource::Builtin, &[set.to_string()]).unwrap();
            let id = |m: &crate::model::Model, s| model_identity(m, s).unwrap();
            assert_ne!(
                id(&base, IdentityScope::Wheel),
                id(&m, IdentityScope::Wheel),
                "{set}"
            );
            assert_eq!(
                id(&base, IdentityScope::Track),
                id(&m, IdentityScope::Track),
                "{set}"
            );
        }
    }
}
