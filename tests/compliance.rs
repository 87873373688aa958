//! `corrugation compliance` end to end on the small model: the table of RPM1–RPM5, rigid and
//! with elastic x-holds, as JSON and CSV. Runs the real binary.

mod common;

use common::{run, SMALL_MODEL};

#[test]
fn compliance_table_of_the_five_models_rigid_and_elastic() {
    let dir = std::env::temp_dir().join(format!(
        "corrugation-compliance-test-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    let mut args: Vec<&str> = vec!["compliance", "--json", "--elastic", "1e9"];
    args.extend(SMALL_MODEL);
    let out = dir.to_str().unwrap().to_string();
    args.extend(["--out", &out]);
    let (code, stdout, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("JSON on stdout");
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 10, "5 models × (rigid, 1e9)");
    let head = |model: &str, hold: &str| {
        rows.iter()
            .find(|r| r["model"] == model && r["hold"] == hold)
            .unwrap()["head_longitudinal_only_m"]
            .as_f64()
            .unwrap()
    };
    for r in rows {
        for k in [
            "head_m",
            "web_m",
            "foot_m",
            "vertical_at_load_m",
            "x_probe_m",
        ] {
            assert!(r[k].as_f64().unwrap().is_finite(), "{k}: {r}");
        }
        println!("{r}");
    }
    // Behavioural (orderings): under the longitudinal force alone one held column is more
    // compliant than a continuous rigid x-hold, and springs are softer than rigid holds.
    assert!(head("RPM3", "rigid") > head("RPM2", "rigid"));
    for m in ["RPM1", "RPM2", "RPM3", "RPM4", "RPM5"] {
        assert!(head(m, "elastic") > head(m, "rigid"), "{m}");
    }
    let csv = std::fs::read_to_string(dir.join("compliance.csv")).unwrap();
    assert_eq!(csv.lines().count(), 11);
    assert!(csv.starts_with("model,hold,hold_stiffness_n_per_m,"));
    // A bad stiffness is an error naming the key.
    let mut bad: Vec<&str> = vec!["compliance", "--elastic=-1", "--variants", "RPM3"];
    bad.extend(SMALL_MODEL);
    bad.extend(["--out", &out]);
    let (code, _, err) = run(&bad);
    assert_ne!(code, 0);
    assert!(err.contains("fastening.hold_stiffness"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
