MODULE DeflexEGM
    !***********************************************************
    ! deflex force-feedback path correction over ABB EGM
    ! (path-correction mode: the RAPID program owns the path,
    ! deflex streams a Cartesian offset every 4 ms).
    !
    ! UNTESTED ON A REAL CONTROLLER. Check every instruction
    ! against the Externally Guided Motion application manual
    ! (3HAC073318-001) of your RobotWare, run it in RobotStudio
    ! with `deflex run` first, then on the robot at low speed.
    !
    ! PC side: CELL.toml with
    !   [robot] kind = "abb-egm", bind = "0.0.0.0:6510",
    !           peer = "<controller IP>:0",
    !           egm_frame = "tool", egm_sensor_rpy_rad = [0, 0, 0],
    !           cycle_s = 0.004
    !   [model] the calibrated model, whose [tool] is tForm below.
    ! Controller side: Configuration > Communication >
    ! Transmission Protocol: a UDPUC device "UCdevice" with the
    ! PC's address and the port of robot.bind (6510 here).
    !***********************************************************

    ! The forming tool. deflex's model must use the same TCP:
    ! the correction is computed at the model's TCP and sent in
    ! this tool's frame (egm_frame = "tool").
    PERS tooldata tForm := [TRUE, [[0, 0, 200], [1, 0, 0, 0]],
                            [3.2, [0, 0, 120], [1, 0, 0, 0], 0, 0, 0]];
    PERS wobjdata wPart := [FALSE, TRUE, "",
                            [[1500, 0, -183], [1, 0, 0, 0]],
                            [[0, 0, 0], [1, 0, 0, 0]]];

    ! EGMActMove's sensor frame, relative to the tool. Identity:
    ! pathCorr x, y, z are along the tool's axes, which is what
    ! deflex sends with egm_frame = "tool" and
    ! egm_sensor_rpy_rad = [0, 0, 0]. If you rotate it, put the
    ! same rotation (roll, pitch, yaw) in egm_sensor_rpy_rad.
    CONST pose sensorFrame := [[0, 0, 0], [1, 0, 0, 0]];

    VAR egmident egmId;

    CONST robtarget pStart := [[0, 0, 20], [0, 0, 1, 0],
                               [0, 0, 0, 0], [9E9, 9E9, 9E9, 9E9, 9E9, 9E9]];
    CONST robtarget p10 := [[40, 0, -1], [0, 0, 1, 0],
                            [0, 0, 0, 0], [9E9, 9E9, 9E9, 9E9, 9E9, 9E9]];
    CONST robtarget p20 := [[0, 40, -2], [0, 0, 1, 0],
                            [0, 0, 0, 0], [9E9, 9E9, 9E9, 9E9, 9E9, 9E9]];
    CONST robtarget p30 := [[-40, 0, -3], [0, 0, 1, 0],
                            [0, 0, 0, 0], [9E9, 9E9, 9E9, 9E9, 9E9, 9E9]];

    PROC main()
        ! Out of contact: deflex tares its sensor here (its
        ! mounting.tare_s, 0.2 s by default) while EGM streams.
        MoveL pStart, v100, fine, tForm \WObj:=wPart;

        EGMReset egmId;
        EGMGetId egmId;
        ! Path correction from the UDPUC device "UCdevice" with the
        ! "default" External Motion Interface Data.
        EGMSetupUC ROB_1, egmId, "default", "UCdevice" \PathCorr \APTR;
        ! Corrections arrive every 4 ms, in sensorFrame (tool).
        EGMActMove egmId, sensorFrame \SampleRate:=4;
        WaitTime 0.5;

        ! The corrected path: EGMMoveL / EGMMoveC instead of
        ! MoveL / MoveC.
        EGMMoveL egmId, p10, v10, z1, tForm \WObj:=wPart;
        EGMMoveC egmId, p20, p30, v10, z1, tForm \WObj:=wPart;
        EGMMoveL egmId, pStart, v10, fine, tForm \WObj:=wPart;

        ! The end of the program: EGM stops streaming, and
        ! `deflex run` reports "phase: ended (robot program
        ! finished)" once it has been silent for --idle-exit-s.
        EGMStop egmId, EGM_STOP_HOLD;
        EGMReset egmId;
    ERROR
        EGMReset egmId;
        RAISE;
    ENDPROC
ENDMODULE
