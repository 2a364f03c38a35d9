//! Stress test of the repair (issue 6): the mean mesh of the hands (quadrilaterals) and of
//! the femurs (hexahedra; the aortas in `tests/aorta.rs`) morphed to the model instances at -3σ and +3σ along each of the
//! first 5 modes, then repaired with the instance as the surface. Every mesh must come out
//! valid with its scaled Jacobians at or above the bound (0.3 quadrilaterals, 0.2
//! hexahedra), its boundary nodes on the instance within 1 % of the median edge length.

use crate::common;

use atlasmesh::model::{Atlas, AtlasParams, ModeSelection};
use common::{check, stress};

#[test]
fn hands_at_three_sigma_are_repaired() {
    let Some(data) = common::data_dir("hands_at_three_sigma_are_repaired") else {
        return;
    };
    let hands = common::hands(&data, Some(2001));
    let atlas = Atlas::build(
        &hands,
        &AtlasParams {
            modes: ModeSelection::Count(11),
            ..Default::default()
        },
    )
    .unwrap();
    let rows = stress(&atlas);
    check("hands", &rows, 0.3);
    let below = rows.iter().filter(|r| r.3 < 0.3).count();
    eprintln!(
        "hands: {below} of {} still below 0.3 after repair",
        rows.len()
    );
}

#[test]
fn femurs_at_three_sigma_are_repaired() {
    let Some(data) = common::data_dir("femurs_at_three_sigma_are_repaired") else {
        return;
    };
    let femurs = common::femurs(&data);
    let atlas = Atlas::build(
        &femurs,
        &AtlasParams {
            modes: ModeSelection::Count(15),
            element_size: 0.02,
            ..Default::default()
        },
    )
    .unwrap();
    let rows = stress(&atlas);
    check("femurs", &rows, 0.2);
    let below = rows.iter().filter(|r| r.3 < 0.2).count();
    eprintln!(
        "femurs: {below} of {} still below 0.2 after repair",
        rows.len()
    );
}
