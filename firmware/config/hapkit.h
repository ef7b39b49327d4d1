/* The Stanford Hapkit 3.0 (and an Arduino Uno with a motor driver wired the same way): what
   the firmware tells the host, and the handle's kinematics. Values from the Hapkit course's
   calibration (docs/firmware.md, "Calibration"); measure your own board's and build with
   -DHFW_CONFIG=<your header>. Lengths in metres, forces in newtons. */
#ifndef HFW_CONFIG_HAPKIT_H
#define HFW_CONFIG_HAPKIT_H

#define HFW_SERIAL "HAPKIT3-0001"       /* 1 to 16 printable ASCII characters */
#define HFW_FIRMWARE_VERSION 0x00010000 /* 1.0.0 */
#define HFW_PERIOD_US 1000              /* 1 kHz */
#define HFW_WATCHDOG_TIMEOUT_US 20000   /* the default after hello: 20 periods */
/* 1: in a version-3 session the board paces the loop, answering each command at its next
   period boundary (docs/protocol.md 5.8); 0: it answers at once, as a version-2 device.
   Off until the firmware's answer fits the period with room for the host (docs/firmware.md,
   "Timing"). */
#define HFW_PACED 1

/* The handle: a capstan of radius r_p on the motor shaft drives a sector of radius r_s; the
   handle is r_h long from the sector's pivot. A motor angle dθ moves the handle by
   r_h (r_p / r_s) dθ. */
#define HFW_HANDLE_RADIUS_M 0.065659
#define HFW_SECTOR_RADIUS_M 0.073152
#define HFW_CAPSTAN_RADIUS_M 0.004191

/* The magnetoresistive sensor on A2: ADC counts per half turn of the motor shaft (the height
   of its sawtooth, 0.0107 degrees of sector per count in the course's calibration) and the
   step that counts as a flip. */
#define HFW_MR_COUNTS_PER_FLIP 964
#define HFW_MR_FLIP_THRESHOLD 700
/* +1 when the counts grow as the handle moves towards +x, else -1. */
#define HFW_POSITION_SIGN 1

/* The quadrature build (HAPTICD_FIRMWARE_SENSOR=quadrature) instead: counts per turn of the
   motor shaft after x4 decoding (a 500-line encoder: 2000). */
#define HFW_ENCODER_COUNTS_PER_REV 2000

/* The motor: torque on the motor shaft at 100 % duty (the course's 0.03 N m) and the force
   limit on the handle, at most the force at full duty. +1 when duty with the direction pin
   low pushes the handle towards +x. */
#define HFW_MOTOR_TORQUE_AT_FULL_DUTY_NM 0.03
#define HFW_FORCE_LIMIT_N 5.0
#define HFW_FORCE_SIGN 1

/* Derived: what the host sees (counts per metre of handle travel; force at full duty). */
#define HFW_PI 3.14159265358979
#define HFW_HANDLE_M_PER_MOTOR_RAD \
    (HFW_HANDLE_RADIUS_M * HFW_CAPSTAN_RADIUS_M / HFW_SECTOR_RADIUS_M)
#define HFW_COUNTS_PER_METER (HFW_MR_COUNTS_PER_FLIP / (HFW_PI * HFW_HANDLE_M_PER_MOTOR_RAD))
#define HFW_FULL_DUTY_FORCE_N (HFW_MOTOR_TORQUE_AT_FULL_DUTY_NM / HFW_HANDLE_M_PER_MOTOR_RAD)

#endif
