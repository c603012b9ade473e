//! The paper's study on the twin (SIMULATED): the lag at force ramps, the Fig. 7 test's points,
//! stiff contact with and without the runaway guard, and a twin campaign calibrated to the
//! plant.

mod fig7;
mod lag;
mod stiff_contact;
mod twin_calibration;
