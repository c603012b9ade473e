//! Integration tests of `deflex-export`: one test binary. Every export is read back and its
//! forward kinematics compared with the robot model's over random configurations: the URDF
//! through deflex's own URDF loader, the UR calibration and the DH table through chains of
//! elementary matrices written out here.

mod round_trip;
