use deflex_calibrate::geometry::fit::*;
use deflex_calibrate::geometry::params::TorsionShape;

#[test]
fn torsion_steps_parse_and_bad_ones_are_named() {
    assert_eq!(
        "torsion:cubic".parse::<Step>(),
        Ok(Step::Torsion(TorsionShape::Cubic))
    );
    assert_eq!(
        " torsion:soft:45 ".parse::<Step>(),
        Ok(Step::Torsion(TorsionShape::Soft(45)))
    );
    for bad in [
        "torsion",
        "torsion:soft",
        "torsion:soft:0",
        "torsion:soft:1001",
    ] {
        assert_eq!(
            bad.parse::<Step>(),
            Err(ChoiceError::UnknownStep(bad.to_string()))
        );
    }
    assert!(Step::Torsion(TorsionShape::Cubic).opt_in());
}
