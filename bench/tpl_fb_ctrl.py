"""Templates: control FUNCTION_BLOCKs (PI controller, totalizer, motor, alarm)."""

from tpl_base import Template, fnum

PI_CTRL = """\
(* PI_CTRL{sfx}
   PI controller with output limits, anti-windup (integration stops at a limit)
   and bumpless manual mode. The setpoint and the process value are scaled
   to percent of range first. *)
FUNCTION_BLOCK PI_CTRL{sfx}
  VAR_INPUT
    sp : REAL;
    pv : REAL;
    cfg : S_CFG{sfx};
    mode : E_MODE{sfx} := {ep}_AUTO;
    man_out : REAL;
    t_cycle : TIME := T#20ms;
  END_VAR
  VAR_OUTPUT
    out : REAL;
    err : REAL;
    at_limit : BOOL;
  END_VAR
  VAR
    integ : REAL;
    dt, ti : REAL;
  END_VAR
  err := SCALE_LIN{sfx}(x := sp) - SCALE_LIN{sfx}(x := pv);
  IF mode = {ep}_MANUAL THEN
    out := LIMIT(cfg.out_min, man_out, cfg.out_max);
    integ := out - cfg.k_p * err;      // bumpless transfer back to AUTO
    at_limit := FALSE;
    RETURN;
  END_IF;
  dt := TIME_TO_REAL(t_cycle) / 1000.0;
  ti := TIME_TO_REAL(cfg.t_i) / 1000.0;
  IF NOT at_limit AND ti > 0.0 THEN
    integ := integ + cfg.k_p * err * dt / ti;
  END_IF;
  out := cfg.k_p * err + integ;
  at_limit := out > cfg.out_max OR out < cfg.out_min;
  out := LIMIT(cfg.out_min, out, cfg.out_max);
END_FUNCTION_BLOCK
"""

TOTALIZER = """\
(* TOTALIZER{sfx}: integrates a flow (units per hour) to a total in LREAL and
   counts every full {unit} units *)
FUNCTION_BLOCK TOTALIZER{sfx}
  VAR_INPUT
    flow : REAL;
    run : BOOL;
    reset : BOOL;
    t_cycle : TIME := T#20ms;
  END_VAR
  VAR_OUTPUT
    total : LREAL;
    units : INT;
    run_time : TIME;
  END_VAR
  VAR
    rst_edge : R_TRIG;
    unit_cnt : CTU;
    portion : LREAL;
    unit_done : BOOL;
  END_VAR
  rst_edge(CLK := reset);
  IF rst_edge.Q THEN
    total := 0.0;
    portion := 0.0;
    run_time := T#0s;
  END_IF;
  unit_done := FALSE;
  IF run AND flow > 0.0 THEN
    portion := portion + REAL_TO_LREAL(flow) * TIME_TO_LREAL(t_cycle) / 3600000.0;
    run_time := run_time + t_cycle;
    IF portion >= {unit} THEN
      total := total + portion;
      portion := 0.0;
      unit_done := TRUE;
    END_IF;
  END_IF;
  unit_cnt(CU := unit_done, R := rst_edge.Q, PV := 32000);
  units := unit_cnt.CV;
END_FUNCTION_BLOCK
"""

MOTOR = """\
(* MOTOR{sfx}
   Motor starter: start delay (horn), feedback supervision, run-on time after
   stop, start counter and run-time meter. A missing feedback after
   T#{fbtime}ms trips the motor ({ep}_FAULT) until reset. *)
FUNCTION_BLOCK MOTOR{sfx}
  VAR_INPUT
    start : BOOL;
    stop : BOOL;
    feedback : BOOL;
    reset : BOOL;
    cfg : S_CFG{sfx};
  END_VAR
  VAR_OUTPUT
    contactor : BOOL;
    horn : BOOL;
    status : S_STATUS{sfx};
  END_VAR
  VAR
    start_edge : R_TRIG;
    reset_edge : R_TRIG;
    t_delay : TON;
    t_fb : TON;
    t_runon : TOF;
    starts : CTU;
  END_VAR
  start_edge(CLK := start);
  reset_edge(CLK := reset);
  CASE status.state OF
    {ep}_IDLE:
      IF start_edge.Q AND NOT stop THEN
        status.state := {ep}_STARTING;
      END_IF;
    {ep}_STARTING:
      IF stop THEN
        status.state := {ep}_IDLE;
      ELSIF t_delay.Q THEN
        status.state := {ep}_RUNNING;
      END_IF;
    {ep}_RUNNING:
      IF stop THEN
        status.state := {ep}_STOPPING;
      ELSIF t_fb.Q THEN
        status.state := {ep}_FAULT;
        status.last_error := {errcode};
      END_IF;
    {ep}_STOPPING:
      IF NOT t_runon.Q THEN
        status.state := {ep}_IDLE;
      END_IF;
    {ep}_FAULT:
      IF reset_edge.Q THEN
        status.state := {ep}_IDLE;
        status.last_error := 0;
      END_IF;
  END_CASE;
  t_delay(IN := status.state = {ep}_STARTING, PT := cfg.start_delay);
  t_fb(IN := status.state = {ep}_RUNNING AND NOT feedback, PT := T#{fbtime}ms);
  t_runon(IN := status.state = {ep}_RUNNING, PT := cfg.run_on);
  contactor := status.state = {ep}_RUNNING OR (status.state = {ep}_STOPPING AND t_runon.Q);
  horn := status.state = {ep}_STARTING;
  starts(CU := status.state = {ep}_RUNNING, R := FALSE, PV := 32767);
  status.starts := INT_TO_DINT(starts.CV);
  IF contactor THEN
    status.run_time := status.run_time + T#20ms;
  END_IF;
  status.text := STATE_TEXT{sfx}(st := status);
END_FUNCTION_BLOCK
"""

ALARM = """\
(* ALARM{sfx}
   Limit alarm with debounced condition, latch and acknowledge.
   Levels: warn above {warn}, alarm above {alarm}, trip above {trip}. *)
FUNCTION_BLOCK ALARM{sfx}
  VAR_INPUT
    value : REAL;
    ack : BOOL;
    now : TIME;
  END_VAR
  VAR_OUTPUT
    level : E_ALARM{sfx};
    active : BOOL;
    unacked : BOOL;
    message : STRING[80];
    since : TIME;
  END_VAR
  VAR
    db : DEBOUNCE{sfx};
    ack_edge : R_TRIG;
    raise_edge : R_TRIG;
    count : CTU;
  END_VAR
  db(in := value > {warn});
  active := db.q;
  IF NOT active THEN
    level := {ep}_OK;
  ELSIF value > {trip} THEN
    level := {ep}_TRIP;
  ELSIF value > {alarm} THEN
    level := {ep}_ALARM;
  ELSE
    level := {ep}_WARN;
  END_IF;
  raise_edge(CLK := active);
  IF raise_edge.Q THEN
    unacked := TRUE;
    since := now;
    message := CONCAT('{stem}{k} limit ', REAL_TO_STRING(value));
  END_IF;
  ack_edge(CLK := ack);
  IF ack_edge.Q THEN
    unacked := FALSE;
  END_IF;
  count(CU := raise_edge.Q, R := FALSE, PV := 9999);
END_FUNCTION_BLOCK
"""


def _alarm_params(rng):
    w = rng.uniform(40, 80)
    return dict(warn=fnum(w), alarm=fnum(w + 10), trip=fnum(w + 20))


TEMPLATES = [
    Template("pi_ctrl", PI_CTRL, fb="PI_CTRL", call="{inst}(sp := 50.0, pv := {r});"),
    Template(
        "totalizer",
        TOTALIZER,
        lambda rng: dict(unit=fnum(rng.choice([0.1, 1, 10, 0.5]))),
        fb="TOTALIZER",
        call="{inst}(flow := {r}, run := {b});",
    ),
    Template(
        "motor",
        MOTOR,
        lambda rng: dict(fbtime=rng.randrange(500, 5000, 100), errcode=rng.randint(100, 999)),
        fb="MOTOR",
        call="{inst}(start := {b}, stop := NOT {b}, feedback := TRUE);",
    ),
    Template("alarm", ALARM, _alarm_params, fb="ALARM", call="{inst}(value := {r});"),
]
