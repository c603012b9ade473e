//! The plan's tables: the technician's sheet against the identifiability table (moved from
//! deflex-stiffness's planner tests when the tables moved here).

use deflex_app::report::plan_tables::{expected_se_rows, technician_rows};
use deflex_calibrate::stiffness::campaign_cell::default_force_n;
use deflex_calibrate::stiffness::plan::{PlanOptions, plan_experiments};
use deflex_model::builtin;

#[test]
fn the_technicians_sheet_agrees_with_the_identifiability_table() {
    for name in ["ur10e", "tx200", "kr210-r2700"] {
        let robot = builtin(name).unwrap();
        let plan = plan_experiments(
            &robot,
            &PlanOptions {
                max_force_n: default_force_n(&robot).unwrap(),
                full_family: true,
                ..PlanOptions::for_a_real_cell()
            },
        )
        .unwrap();
        let not_identifiable: Vec<&str> = plan
            .expected
            .iter()
            .filter(|e| !e.identifiable())
            .map(|e| e.label.as_str())
            .collect();
        assert!(
            !not_identifiable.is_empty(),
            "{name}: the wrist is not identifiable from TCP forces"
        );
        let sheet = technician_rows(&plan);
        let table = expected_se_rows(&plan);
        for e in &plan.expected {
            if plan.axis_cases.iter().any(|a| a.id == e.id) {
                assert!(e.identifiable(), "{name}: {} has an axis case", e.label);
            }

            let row = table.iter().find(|r| r[0] == e.label).unwrap();
            if !e.identifiable() {
                assert_eq!(row[3], "not identifiable");
                assert_eq!(row[4], "-", "{name} {}: {row:?}", e.label);
                for line in &sheet {
                    assert!(
                        !line[5].split(' ').any(|w| w == e.label),
                        "{name}: case {} is there for {}, which the table calls not identifiable",
                        line[0],
                        e.label
                    );
                }
            }
        }
        // Every axis-by-axis case named in the table is on the sheet for that eDoF.
        for a in &plan.axis_cases {
            let label = deflex_calibrate::stiffness::edof_label(a.id);
            let line = sheet.iter().find(|l| l[0] == a.load_case).unwrap();
            assert!(
                line[5].split(' ').any(|w| w == label),
                "{name}: {line:?} should name {label}"
            );
        }
    }
}
