"""Templates: the sequencer and the station FB that nests the module's other FBs."""

from tpl_base import Template, fnum

SEQUENCER = """\
(* SEQUENCER{sfx}
   Step sequencer with {nsteps} timed steps. Each step has its own duration;
   the sequence restarts when `cyclic` is set. Outputs one bit per step. *)
FUNCTION_BLOCK SEQUENCER{sfx}
  VAR_INPUT
    run : BOOL;
    cyclic : BOOL := TRUE;
    next : BOOL;                  // manual step forward
  END_VAR
  VAR_OUTPUT
    step : INT;
    outputs : WORD;
    remaining : TIME;
    progress : INT;
    done : BOOL;
  END_VAR
  VAR
    durations : ARRAY[1..{nsteps}] OF TIME := [{durations}];
    timers : ARRAY[1..{nsteps}] OF TON;
    next_edge : R_TRIG;
    i : INT;
  END_VAR
  next_edge(CLK := next);
  IF NOT run THEN
    step := 0;
    done := FALSE;
  ELSIF step = 0 THEN
    step := 1;
  END_IF;
  FOR i := 1 TO {nsteps} DO
    timers[i](IN := run AND step = i, PT := durations[i]);
  END_FOR;
  IF step > 0 THEN
    remaining := TIME_LEFT{sfx}(elapsed := timers[step].ET, total := durations[step], percent => progress);
    IF timers[step].Q OR next_edge.Q THEN
      IF step < {nsteps} THEN
        step := step + 1;
      ELSIF cyclic THEN
        step := 1;
      ELSE
        done := TRUE;
      END_IF;
    END_IF;
  END_IF;
  outputs := 0;
  IF step > 0 THEN
    outputs := SHL(WORD#1, step - 1);
  END_IF;
END_FUNCTION_BLOCK
"""


def _seq_params(rng):
    n = rng.randint(3, 8)
    return dict(nsteps=n, durations=", ".join(f"T#{rng.randrange(100, 3000, 20)}ms" for _ in range(n)))


STATION = """\
(* ==========================================================================
   STATION{sfx}
   One {stem} station: analog input -> linearisation -> filter -> PI control
   of the {stem}, motor starter, limit alarm, flow totalizer, status telegram.
   ========================================================================== *)
FUNCTION_BLOCK STATION{sfx}
  VAR_INPUT
    enable : BOOL;
    setpoint : REAL := {sp};
    raw_pv : INT;
    ack : BOOL;
    now : TIME;
  END_VAR
  VAR_OUTPUT
    out_raw : INT;
    running : BOOL;
    alarm_level : E_ALARM{sfx};
    crc : WORD;
    flags : WORD;
    text : STRING[64];
  END_VAR
  VAR
    cfg : S_CFG{sfx};
    coef : T_COEF{sfx} := [{coefs}];
    curve : T_CURVE{sfx} := [{points}];
    pv_filter : FILTER_PT1{sfx};
    sp_ramp : RAMP{sfx};
    ctrl : PI_CTRL{sfx};
    drive : MOTOR{sfx};
    limit_alarm : ALARM{sfx};
    stats : MOV_AVG{sfx};
    flow_total : TOTALIZER{sfx};
    level_switch : HYST{sfx};
    lamp : BLINK{sfx};
    seq : SEQUENCER{sfx};
    telegram : T_BYTES{sfx};
    pv, pv_lin, valve, flow : REAL;
    wire_break, over : BOOL;
    i : INT;
    days : INT;
  END_VAR
  (* measurement *)
  pv := RAW_TO_ENG{sfx}(raw := raw_pv, eng_lo := 0.0, eng_hi := 100.0,
                        wire_break => wire_break, overrange => over);
  pv_lin := POLY{sfx}(x := pv, c := coef);
  pv_filter(x := pv_lin);
  stats(x := pv_filter.y);
  // control
  sp_ramp(target := setpoint, hold := NOT enable);
  ctrl(sp := sp_ramp.out, pv := pv_filter.y, cfg := cfg);
  valve := CURVE_LOOKUP{sfx}(curve := curve, x := ctrl.out);
  out_raw := ENG_TO_RAW{sfx}(value := valve, eng_lo := cfg.out_min, eng_hi := cfg.out_max);
  drive(start := enable, stop := NOT enable OR wire_break, feedback := TRUE, reset := ack, cfg := cfg);
  running := drive.contactor;
  flow := valve * {flow_gain};
  flow_total(flow := flow, run := running);
  limit_alarm(value := pv_filter.y, ack := ack, now := now);
  alarm_level := limit_alarm.level;
  level_switch(x := pv_filter.y);
  lamp(enable := limit_alarm.unacked);
  seq(run := running);
  (* status telegram *)
  flags := PACK_BITS{sfx}(b0 := running, b1 := wire_break, b2 := over, b3 := lamp.q,
                          b4 := level_switch.q, b5 := stats.noisy, b6 := ctrl.at_limit, b7 := seq.done);
  telegram[1] := WORD_TO_BYTE(flags);
  telegram[2] := WORD_TO_BYTE(SHR(flags, 8));
  telegram[3] := INT_TO_BYTE(out_raw MOD 256);
  telegram[4] := INT_TO_BYTE(seq.step);
  FOR i := 5 TO {nbytes} DO
    telegram[i] := INT_TO_BYTE((i * {mult} + flow_total.units) MOD 256);
  END_FOR;
  crc := CRC16{sfx}(data := telegram, n := {nbytes});
  days := DAYS_IN_MONTH{sfx}(year := 2024, month := seq.step + 1);
  text := drive.status.text;
END_FUNCTION_BLOCK
"""


def _station_params(rng):
    return dict(sp=fnum(rng.uniform(20, 80)), flow_gain=fnum(rng.uniform(0.1, 3)), mult=rng.randint(3, 97))


TEMPLATES = [
    Template("sequencer", SEQUENCER, _seq_params, fb="SEQUENCER", call="{inst}(run := {b});"),
    Template(
        "station", STATION, _station_params, fb="STATION", call="{inst}(enable := {b}, raw_pv := {i}, now := {t});"
    ),
]
