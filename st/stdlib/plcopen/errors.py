"""ErrorID values of the motion function blocks (PLCopen leaves them to the implementation).

0x1xxx: the axis state forbids the command; 0x2xxx: a parameter is invalid; 0x3xxx: an axis,
drive or communication error (these also show in MC_ReadAxisError.AxisErrorID).
"""

from enum import IntEnum


class E(IntEnum):
    OK = 0x0000
    AXIS_DISABLED = 0x1001  # a motion command while the axis is Disabled (power off)
    AXIS_ERRORSTOP = 0x1002  # any command in ErrorStop; also the active and buffered FBs on entering it
    AXIS_STOPPING = 0x1003  # a motion command while MC_Stop is active or held
    AXIS_HOMING = 0x1004  # a motion command during Homing
    INVALID_STATE = 0x1005  # MC_Home while moving, MC_SetPosition while Homing or in ErrorStop
    NO_ERROR_TO_RESET = 0x1006  # MC_Reset outside ErrorStop
    STOP_ALREADY_ACTIVE = 0x1007  # a second MC_Stop while Stopping
    POWER_ALREADY_ACTIVE = 0x1008  # a second MC_Power instance on the axis
    BUFFER_FULL = 0x1010  # more buffered commands than the axis's buffer_size
    INVALID_VELOCITY = 0x2001
    INVALID_ACCELERATION = 0x2002
    INVALID_DECELERATION = 0x2003
    INVALID_JERK = 0x2004
    INVALID_DIRECTION = 0x2005
    INVALID_POSITION = 0x2006  # NaN/inf, or outside [0, period) on a modulo axis
    INVALID_BUFFER_MODE = 0x2007
    SW_LIMIT_TARGET = 0x2008  # the target lies outside the software limits (rejected up front)
    INVALID_AXIS_REF = 0x2009
    HOMING_NOT_CONFIGURED = 0x200A  # MC_Home with homing = "switch" but no switch configured
    INVALID_EXECUTION_MODE = 0x200B  # MC_SetPosition: an ExecutionMode outside MC_EXECUTION_MODE
    DRIVE_FAULT = 0x3001
    COMMUNICATION_LOST = 0x3002
    POWER_STAGE_LOST = 0x3003
    ENABLE_TIMEOUT = 0x3004  # MC_Power: the power stage did not come on within enable_timeout
    FOLLOWING_ERROR = 0x3005
    SW_LIMIT_REACHED = 0x3006  # the set position ran into a software limit
    RESET_FAILED = 0x3007
    HOMING_FAILED = 0x3008  # MC_Home: no switch edge within home_search_distance
