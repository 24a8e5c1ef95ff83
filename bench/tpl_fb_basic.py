"""Templates: small FUNCTION_BLOCKs (filters, hysteresis, debounce, averaging, ramps, blink)."""

from tpl_base import Template, fnum

FILTER_PT1 = """\
(* FILTER_PT1{sfx}
   First order lag: y := y + (x - y) * dt / (T + dt). dt is the task cycle time.
   The first call (or rst) loads the input directly. *)
FUNCTION_BLOCK FILTER_PT1{sfx}
  VAR_INPUT
    x : REAL;
    t_filter : TIME := T#{tf}ms;
    t_cycle : TIME := T#20ms;
    rst : BOOL;
  END_VAR
  VAR_OUTPUT
    y : REAL;
  END_VAR
  VAR
    init : BOOL;
    dt, tf : REAL;
  END_VAR
  dt := TIME_TO_REAL(t_cycle);
  tf := TIME_TO_REAL(t_filter);
  IF NOT init OR rst OR tf <= 0.0 THEN
    y := x;
    init := TRUE;
  ELSE
    y := y + (x - y) * dt / (tf + dt);
  END_IF;
END_FUNCTION_BLOCK
"""

HYST = """\
(* HYST{sfx}: two-point switch with hysteresis; counts the switching operations *)
FUNCTION_BLOCK HYST{sfx}
  VAR_INPUT
    x : REAL;
    on_level : REAL := {on};
    off_level : REAL := {off};
  END_VAR
  VAR_OUTPUT
    q : BOOL;
    switches : INT;
  END_VAR
  VAR
    edge : R_TRIG;
    cnt : CTU;
  END_VAR
  IF x >= on_level THEN
    q := TRUE;
  ELSIF x <= off_level THEN
    q := FALSE;
  END_IF;
  edge(CLK := q);
  cnt(CU := edge.Q, R := FALSE, PV := 32000);
  switches := cnt.CV;
END_FUNCTION_BLOCK
"""


def _hyst_params(rng):
    off = rng.uniform(5, 60)
    return dict(off=fnum(off), on=fnum(off + rng.uniform(1, 20)))


DEBOUNCE = """\
(* DEBOUNCE{sfx}: input filter for mechanical contacts; on delay and off delay *)
FUNCTION_BLOCK DEBOUNCE{sfx}
  VAR_INPUT
    in : BOOL;
    t_on : TIME := T#{ton}ms;
    t_off : TIME := T#{toff}ms;
  END_VAR
  VAR_OUTPUT
    q : BOOL;
  END_VAR
  VAR
    on_delay : TON;
    off_delay : TOF;
  END_VAR
  on_delay(IN := in, PT := t_on);
  off_delay(IN := on_delay.Q, PT := t_off);
  q := off_delay.Q;
END_FUNCTION_BLOCK
"""

MOV_AVG = """\
(* MOV_AVG{sfx}: moving average over the last {size} samples (ring buffer) with
   the statistics of the window *)
FUNCTION_BLOCK MOV_AVG{sfx}
  VAR_INPUT
    x : REAL;
    sample : BOOL := TRUE;
  END_VAR
  VAR_OUTPUT
    avg : REAL;
    lo, hi, sdev : REAL;
    noisy : BOOL;
  END_VAR
  VAR
    buf : T_BUF{sfx};
    idx : INT;
    n : INT;
  END_VAR
  IF sample THEN
    buf[idx] := x;
    idx := (idx + 1) MOD {size};
    IF n < {size} THEN
      n := n + 1;
    END_IF;
  END_IF;
  IF n > 0 THEN
    noisy := ARRAY_STATS{sfx}(buf := buf, n := n, lo => lo, hi => hi, mean => avg, sdev => sdev);
  END_IF;
END_FUNCTION_BLOCK
"""

RAMP = """\
(* RAMP{sfx}: rate limiter; the output follows the target at most `rate` units per second *)
FUNCTION_BLOCK RAMP{sfx}
  VAR_INPUT
    target : REAL;
    rate : REAL := {rate};
    t_cycle : TIME := T#20ms;
    hold : BOOL;
  END_VAR
  VAR_OUTPUT
    out : REAL;
    busy : BOOL;
  END_VAR
  VAR
    step : REAL;
  END_VAR
  step := ABS(rate) * TIME_TO_REAL(t_cycle) / 1000.0;
  busy := FALSE;
  IF hold THEN
    RETURN;
  END_IF;
  IF out < target - step THEN
    out := out + step;
    busy := TRUE;
  ELSIF out > target + step THEN
    out := out - step;
    busy := TRUE;
  ELSE
    out := target;
  END_IF;
END_FUNCTION_BLOCK
"""

BLINK = """\
(* BLINK{sfx}: flashing signal, {pon} ms on / {poff} ms off, plus a short pulse
   at each switch-on *)
FUNCTION_BLOCK BLINK{sfx}
  VAR_INPUT
    enable : BOOL;
  END_VAR
  VAR_OUTPUT
    q : BOOL;
    pulse : BOOL;
    cycles : INT;
  END_VAR
  VAR
    t_on : TON;
    t_off : TON;
    p : TP;
    trig : R_TRIG;
  END_VAR
  IF NOT enable THEN
    q := FALSE;
    t_on(IN := FALSE);
    t_off(IN := FALSE);
  ELSE
    t_on(IN := NOT q, PT := T#{poff}ms);
    t_off(IN := q, PT := T#{pon}ms);
    IF t_on.Q THEN
      q := TRUE;
    ELSIF t_off.Q THEN
      q := FALSE;
    END_IF;
  END_IF;
  trig(CLK := q);
  p(IN := trig.Q, PT := T#{ppulse}ms);
  pulse := p.Q;
  IF trig.Q THEN
    cycles := cycles + 1;
  END_IF;
END_FUNCTION_BLOCK
"""


TEMPLATES = [
    Template(
        "filter_pt1",
        FILTER_PT1,
        lambda rng: dict(tf=rng.randrange(100, 10000, 50)),
        fb="FILTER_PT1",
        call="{inst}(x := {r}, t_cycle := T#20ms);",
    ),
    Template("hyst", HYST, _hyst_params, fb="HYST", call="{inst}(x := {r});"),
    Template(
        "debounce",
        DEBOUNCE,
        lambda rng: dict(ton=rng.randrange(10, 200, 10), toff=rng.randrange(10, 500, 10)),
        fb="DEBOUNCE",
        call="{inst}(in := {b});",
    ),
    Template("mov_avg", MOV_AVG, fb="MOV_AVG", call="{inst}(x := {r});"),
    Template("ramp", RAMP, lambda rng: dict(rate=fnum(rng.uniform(0.5, 25))), fb="RAMP", call="{inst}(target := {r});"),
    Template(
        "blink",
        BLINK,
        lambda rng: dict(
            pon=rng.randrange(100, 2000, 20), poff=rng.randrange(100, 2000, 20), ppulse=rng.randrange(20, 100, 20)
        ),
        fb="BLINK",
        call="{inst}(enable := {b});",
    ),
]
