"""Templates: numeric FUNCTIONs (scaling, limits, polynomials, array statistics, curves)."""

from tpl_base import Template, fnum

SCALE_LIN = """\
(* SCALE_LIN{sfx}
   Linear scaling of x from [in_lo, in_hi] to [out_lo, out_hi], clamped to the
   output range. A degenerate input range returns out_lo. *)
FUNCTION SCALE_LIN{sfx} : REAL
  VAR_INPUT
    x : REAL;
    in_lo : REAL := {in_lo};
    in_hi : REAL := {in_hi};
    out_lo : REAL := {out_lo};
    out_hi : REAL := {out_hi};
  END_VAR
  VAR
    span : REAL;
  END_VAR
  span := in_hi - in_lo;
  IF ABS(span) < 1.0E-6 THEN
    SCALE_LIN{sfx} := out_lo;   // nothing sensible to do
    RETURN;
  END_IF;
  SCALE_LIN{sfx} := LIMIT(MIN(out_lo, out_hi),
                          out_lo + (x - in_lo) * (out_hi - out_lo) / span,
                          MAX(out_lo, out_hi));
END_FUNCTION
"""


def _scale_params(rng):
    lo = rng.choice([0, 4, -10, 0])
    olo = rng.choice([0, -50, 0, 10])
    return dict(
        in_lo=fnum(lo),
        in_hi=fnum(lo + rng.choice([16, 20, 100, 27648])),
        out_lo=fnum(olo),
        out_hi=fnum(olo + rng.uniform(10, 500)),
    )


RAW_TO_ENG = """\
(* RAW_TO_ENG{sfx}
   Converts a raw analog input word (0..{raw_max}) to engineering units and
   detects wire break / overrange. *)
FUNCTION RAW_TO_ENG{sfx} : REAL
  VAR_INPUT
    raw : INT;
    eng_lo : REAL;
    eng_hi : REAL;
  END_VAR
  VAR_OUTPUT
    wire_break : BOOL;
    overrange : BOOL;
  END_VAR
  VAR
    r : REAL;
  END_VAR
  wire_break := raw < {raw_wb};
  overrange := raw > {raw_max};
  r := INT_TO_REAL(LIMIT(0, raw, {raw_max})) / {raw_max}.0;
  RAW_TO_ENG{sfx} := eng_lo + r * (eng_hi - eng_lo);
END_FUNCTION
"""


def _raw_params(rng):
    return dict(raw_max=rng.choice([27648, 32000, 4095, 16383]), raw_wb=-rng.randint(50, 900))


ENG_TO_RAW = """\
(* ENG_TO_RAW{sfx}: engineering value -> analog output word, rounded and limited *)
FUNCTION ENG_TO_RAW{sfx} : INT
  VAR_INPUT
    value : REAL;
    eng_lo : REAL;
    eng_hi : REAL;
  END_VAR
  VAR
    frac : REAL;
    raw : DINT;
  END_VAR
  IF eng_hi <= eng_lo THEN
    ENG_TO_RAW{sfx} := 0;
    RETURN;
  END_IF;
  frac := (value - eng_lo) / (eng_hi - eng_lo);
  raw := REAL_TO_DINT(frac * {raw_max}.0);
  ENG_TO_RAW{sfx} := DINT_TO_INT(LIMIT(0, raw, {raw_max}));
END_FUNCTION
"""

POLY = """\
(* POLY{sfx}: evaluates c[0] + c[1]*x + ... + c[{ncoef}]*x^n by Horner's rule in
   double precision. Used for sensor linearisation. *)
FUNCTION POLY{sfx} : REAL
  VAR_INPUT
    x : REAL;
    c : T_COEF{sfx};
  END_VAR
  VAR
    i : INT;
    acc : LREAL;
  END_VAR
  acc := 0.0;
  FOR i := {ncoef} TO 0 BY -1 DO
    acc := acc * x + c[i];   (* REAL widens to LREAL *)
  END_FOR;
  POLY{sfx} := LREAL_TO_REAL(acc);
END_FUNCTION
"""

ARRAY_STATS = """\
(* ARRAY_STATS{sfx}
   Minimum, maximum, mean and standard deviation of a sample buffer. *)
FUNCTION ARRAY_STATS{sfx} : BOOL
  VAR_INPUT
    buf : T_BUF{sfx};
    n : INT;                 (* number of valid samples, 1..{size} *)
  END_VAR
  VAR_OUTPUT
    lo : REAL;
    hi : REAL;
    mean : REAL;
    sdev : REAL;
  END_VAR
  VAR
    i, last : INT;
    sum, sq : LREAL;
  END_VAR
  last := LIMIT(1, n, {size}) - 1;
  lo := buf[0];
  hi := buf[0];
  sum := 0.0;
  sq := 0.0;
  FOR i := 0 TO last DO
    IF buf[i] < lo THEN lo := buf[i]; END_IF;
    IF buf[i] > hi THEN hi := buf[i]; END_IF;
    sum := sum + buf[i];
    sq := sq + buf[i] * buf[i];
  END_FOR;
  mean := LREAL_TO_REAL(sum / INT_TO_LREAL(last + 1));
  sdev := LREAL_TO_REAL(SQRT(MAX(0.0, sq / INT_TO_LREAL(last + 1) - mean * mean)));
  ARRAY_STATS{sfx} := hi - lo > {spread};
END_FUNCTION
"""

CURVE_LOOKUP = """\
(* CURVE_LOOKUP{sfx}
   Piecewise linear interpolation in a table of points sorted by x.
   Below the first / above the last point the end values are held. *)
FUNCTION CURVE_LOOKUP{sfx} : REAL
  VAR_INPUT
    curve : T_CURVE{sfx};
    x : REAL;
  END_VAR
  VAR
    i : INT;
    dx : REAL;
  END_VAR
  IF x <= curve[1].x THEN
    CURVE_LOOKUP{sfx} := curve[1].y;
    RETURN;
  END_IF;
  i := 2;
  WHILE i < {npts} AND x > curve[i].x DO
    i := i + 1;
  END_WHILE;
  IF x >= curve[i].x THEN
    CURVE_LOOKUP{sfx} := curve[i].y;
  ELSE
    dx := curve[i].x - curve[i - 1].x;
    IF dx > 0.0 THEN
      CURVE_LOOKUP{sfx} := curve[i - 1].y + (x - curve[i - 1].x) * (curve[i].y - curve[i - 1].y) / dx;
    ELSE
      CURVE_LOOKUP{sfx} := curve[i].y;
    END_IF;
  END_IF;
END_FUNCTION
"""


TEMPLATES = [
    Template("scale_lin", SCALE_LIN, _scale_params),
    Template("raw_to_eng", RAW_TO_ENG, _raw_params),
    Template("eng_to_raw", ENG_TO_RAW, _raw_params),
    Template("poly", POLY),
    Template("array_stats", ARRAY_STATS, lambda rng: dict(spread=fnum(rng.uniform(0.5, 50)))),
    Template("curve_lookup", CURVE_LOOKUP),
]
