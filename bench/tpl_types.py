"""Template: the TYPE block of one library module (enums, structs, arrays, a subrange).

Every template module exports TEMPLATES, a list of `Template`s (see gen_library.py).
Placeholders: {sfx} (POU name suffix), {ep} (enum member prefix), {stem}, {k}, plus the
constants returned by the template's params function.
"""

from tpl_base import Template, fnum

TYPES = """\
(* ==========================================================================
   Module {stem} #{k} -- data types
   ----------------------------------------------------------------------
   State and mode enumerations, the status and configuration records and
   the buffers used by the {stem} function blocks of this module.
   ========================================================================== *)
TYPE
  E_STATE{sfx} : ({ep}_IDLE, {ep}_STARTING, {ep}_RUNNING, {ep}_STOPPING, {ep}_FAULT);
  E_MODE{sfx} : ({ep}_MANUAL, {ep}_AUTO, {ep}_CASCADE) := {ep}_AUTO;
  E_ALARM{sfx} : ({ep}_OK, {ep}_WARN, {ep}_ALARM, {ep}_TRIP);
  T_BUF{sfx} : ARRAY[0..{size_m1}] OF REAL;         // ring buffer of samples
  T_BYTES{sfx} : ARRAY[1..{nbytes}] OF BYTE;        // telegram bytes
  T_COEF{sfx} : ARRAY[0..{ncoef}] OF REAL;          // polynomial coefficients
  T_PCT{sfx} : INT (0..100);                        // percent, checked at run time
  S_POINT{sfx} : STRUCT
    x : REAL;
    y : REAL;
  END_STRUCT;
  T_CURVE{sfx} : ARRAY[1..{npts}] OF S_POINT{sfx};
  S_STATUS{sfx} : STRUCT
    state : E_STATE{sfx};
    mode : E_MODE{sfx};
    alarm : E_ALARM{sfx};
    starts : DINT;
    run_time : TIME;
    last_error : INT;
    text : STRING[64];
  END_STRUCT;
  S_CFG{sfx} : STRUCT
    k_p : REAL := {kp};          (* proportional gain *)
    t_i : TIME := T#{ti}ms;      (* integral time *)
    out_min : REAL := {omin};
    out_max : REAL := {omax};
    start_delay : TIME := T#{sdelay}ms;
    run_on : TIME := T#{runon}ms;
  END_STRUCT;
END_TYPE
"""


def _types_params(rng):
    omin = rng.choice([0, -10, -100, 0, 4])
    return dict(
        kp=fnum(rng.uniform(0.2, 8.0)),
        ti=rng.randrange(500, 20000, 100),
        omin=fnum(omin),
        omax=fnum(omin + rng.choice([100, 20, 1000])),
        sdelay=rng.randrange(200, 5000, 50),
        runon=rng.randrange(100, 3000, 50),
    )


TEMPLATES = [Template("types", TYPES, _types_params)]
