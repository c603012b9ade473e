use deflex_calibrate::geometry::params::{EgModel, TorsionShape, TorsionTerm};
use deflex_calibrate::geometry::terms::*;

fn ur10() -> EgModel {
    EgModel::from_robot(&deflex_model::builtin("ur10").expect("built-in"))
}

fn terms(model: &EgModel, torsion: Vec<TorsionRecord>) -> CalibrationTerms {
    CalibrationTerms {
        format: FORMAT,
        geometry_fingerprint: model.robot.geometry_fingerprint(),
        kept_steps: Vec::new(),
        harmonics: Vec::new(),
        backlash_rad: vec![0.0; model.robot.joint_count()],
        torsion,
        residual_model: None,
        joint_maps: None,
        fit_rms_m: 4e-4,
        held_out_rms_m: None,
    }
}

fn record(edof: &str, shape: &str, scale: u16, value: f64) -> TorsionRecord {
    TorsionRecord {
        edof: edof.into(),
        shape: shape.into(),
        torque_scale_nm: scale,
        value_rad_per_nm: value,
    }
}

#[test]
fn torsion_terms_round_trip_and_bad_ones_are_refused() {
    let mut model = ur10();
    let written = terms(
        &model,
        vec![
            record("J2.z", "soft", 45, 1.5e-5),
            record("J3.z", "cubic", 0, -3e-6),
        ],
    );
    assert!(!written.is_empty());
    let read =
        CalibrationTerms::from_json(&written.to_json().expect("serialises")).expect("round trip");
    read.apply(&mut model).expect("applies");
    let j2 = model.robot.edofs().position(|e| e.label() == "J2.z");
    assert_eq!(
        model.torsion[0],
        TorsionTerm {
            edof: j2.expect("J2.z"),
            shape: TorsionShape::Soft(45),
            value: 1.5e-5
        }
    );
    assert_eq!(model.torsion[1].shape, TorsionShape::Cubic);
    // A file written before torsion terms existed still reads.
    let old = written
        .to_json()
        .expect("serialises")
        .replace("\"torsion\"", "\"unused\"");
    assert!(
        CalibrationTerms::from_json(&old)
            .expect("old")
            .torsion
            .is_empty()
    );
    for (bad, what) in [
        (record("J9.z", "cubic", 0, 1e-6), "J9.z"),
        (record("J2.z", "soft", 0, 1e-6), "soft"),
        (record("J2.z", "quartic", 0, 1e-6), "quartic"),
        (record("J2.z", "cubic", 0, f64::NAN), "NaN"),
    ] {
        let error = terms(&model, vec![bad])
            .apply(&mut ur10())
            .expect_err("refused")
            .to_string();
        assert!(error.contains(what), "{error}");
    }
}
