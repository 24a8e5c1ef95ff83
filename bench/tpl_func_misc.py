"""Templates: FUNCTIONs on bits, strings, times and calendars."""

from tpl_base import Template

CRC16 = """\
(* CRC16{sfx}
   CRC-16 (polynomial 16#{poly}) over the first n bytes of a telegram, bit by bit.
   Init value 16#{init}; the result is not inverted. *)
FUNCTION CRC16{sfx} : WORD
  VAR_INPUT
    data : T_BYTES{sfx};
    n : INT;
  END_VAR
  VAR
    i, b : INT;
    crc : WORD;
  END_VAR
  crc := 16#{init};
  FOR i := 1 TO LIMIT(0, n, {nbytes}) DO
    crc := crc XOR BYTE_TO_WORD(data[i]);
    FOR b := 1 TO 8 DO
      IF (crc AND 16#0001) <> 0 THEN
        crc := SHR(crc, 1) XOR 16#{poly};
      ELSE
        crc := SHR(crc, 1);
      END_IF;
    END_FOR;
  END_FOR;
  CRC16{sfx} := crc;
END_FUNCTION
"""


def _crc_params(rng):
    return dict(poly=rng.choice(["A001", "8408", "1021", "C002"]), init=rng.choice(["FFFF", "0000", "1D0F"]))


STATE_TEXT = """\
(* STATE_TEXT{sfx}: human-readable status line for the HMI, e.g.
   '{stem}{k}: RUNNING (AUTO) starts=12 t=T#1h2m' *)
FUNCTION STATE_TEXT{sfx} : STRING[64]
  VAR_INPUT
    st : S_STATUS{sfx};
  END_VAR
  VAR
    s, m : STRING[64];
  END_VAR
  CASE st.state OF
    {ep}_IDLE: s := 'IDLE';
    {ep}_STARTING: s := 'STARTING';
    {ep}_RUNNING: s := 'RUNNING';
    {ep}_STOPPING: s := 'STOPPING';
  ELSE
    s := CONCAT('FAULT ', INT_TO_STRING(st.last_error));
  END_CASE;
  CASE st.mode OF
    {ep}_MANUAL: m := 'MAN';
    {ep}_AUTO: m := 'AUTO';
  ELSE
    m := 'CASC';
  END_CASE;
  s := CONCAT('{stem}{k}: ', s, ' (', m, ') starts=', DINT_TO_STRING(st.starts));
  s := CONCAT(s, ' t=', TIME_TO_STRING(st.run_time));
  IF LEN(s) > {maxlen} THEN
    s := CONCAT(LEFT(s, {maxlen_m3}), '...');   // keep the HMI field short
  END_IF;
  STATE_TEXT{sfx} := s;
END_FUNCTION
"""

PARSE_KV = """\
(* PARSE_KV{sfx}
   Reads the integer value of a 'key=value;' pair out of a text telegram.
   Returns default_value when the key is missing. *)
FUNCTION PARSE_KV{sfx} : DINT
  VAR_INPUT
    text : STRING[120];
    key : STRING[16];
    default_value : DINT;
  END_VAR
  VAR
    rest : STRING[120];
    p, q : INT;
  END_VAR
  p := FIND(text, CONCAT(key, '='));
  IF p = 0 THEN
    PARSE_KV{sfx} := default_value;
    RETURN;
  END_IF;
  rest := MID(text, LEN(text) - p - LEN(key), p + LEN(key) + 1);
  q := FIND(rest, ';');
  IF q > 0 THEN
    rest := LEFT(rest, q - 1);
  END_IF;
  IF LEN(rest) = 0 THEN
    PARSE_KV{sfx} := default_value;
  ELSE
    PARSE_KV{sfx} := STRING_TO_DINT(rest);
  END_IF;
END_FUNCTION
"""

TIME_LEFT = """\
(* TIME_LEFT{sfx}: remaining time of a running interval and its progress in percent *)
FUNCTION TIME_LEFT{sfx} : TIME
  VAR_INPUT
    elapsed : TIME;
    total : TIME;
  END_VAR
  VAR_OUTPUT
    percent : INT;
  END_VAR
  VAR
    ms_total : DINT;
  END_VAR
  ms_total := TIME_TO_DINT(total);
  IF ms_total <= 0 OR elapsed >= total THEN
    percent := 100;
    TIME_LEFT{sfx} := T#0s;
    RETURN;
  END_IF;
  percent := DINT_TO_INT(TIME_TO_DINT(elapsed) * 100 / ms_total);
  TIME_LEFT{sfx} := total - elapsed;
  IF TIME_LEFT{sfx} < T#{grace}ms THEN
    TIME_LEFT{sfx} := T#0s;   (* below the display resolution *)
  END_IF;
END_FUNCTION
"""

DAYS_IN_MONTH = """\
(* DAYS_IN_MONTH{sfx}: number of days of a month, Gregorian leap years *)
FUNCTION DAYS_IN_MONTH{sfx} : INT
  VAR_INPUT
    year : INT;
    month : INT;
  END_VAR
  CASE month OF
    1, 3, 5, 7, 8, 10, 12:
      DAYS_IN_MONTH{sfx} := 31;
    4, 6, 9, 11:
      DAYS_IN_MONTH{sfx} := 30;
    2:
      IF (year MOD 4 = 0 AND year MOD 100 <> 0) OR year MOD 400 = 0 THEN
        DAYS_IN_MONTH{sfx} := 29;
      ELSE
        DAYS_IN_MONTH{sfx} := 28;
      END_IF;
  ELSE
    DAYS_IN_MONTH{sfx} := 0;   // invalid month
  END_CASE;
END_FUNCTION
"""

PACK_BITS = """\
(* PACK_BITS{sfx}: packs eight flags into a status byte and adds a parity bit
   in the high byte of the returned word *)
FUNCTION PACK_BITS{sfx} : WORD
  VAR_INPUT
    b0, b1, b2, b3, b4, b5, b6, b7 : BOOL;
  END_VAR
  VAR
    w : WORD;
    n, i : INT;
  END_VAR
  w := BOOL_TO_WORD(b0) OR SHL(BOOL_TO_WORD(b1), 1) OR SHL(BOOL_TO_WORD(b2), 2)
       OR SHL(BOOL_TO_WORD(b3), 3) OR SHL(BOOL_TO_WORD(b4), 4) OR SHL(BOOL_TO_WORD(b5), 5)
       OR SHL(BOOL_TO_WORD(b6), 6) OR SHL(BOOL_TO_WORD(b7), 7);
  n := 0;
  FOR i := 0 TO 7 DO
    IF (SHR(w, i) AND 16#0001) = 16#0001 THEN
      n := n + 1;
    END_IF;
  END_FOR;
  IF n MOD 2 = {parity} THEN
    w := w OR 16#{pmask};
  END_IF;
  PACK_BITS{sfx} := w;
END_FUNCTION
"""


TEMPLATES = [
    Template("crc16", CRC16, _crc_params),
    Template(
        "state_text", STATE_TEXT, lambda rng: (lambda m: dict(maxlen=m, maxlen_m3=m - 3))(rng.choice([48, 56, 60]))
    ),
    Template("parse_kv", PARSE_KV),
    Template("time_left", TIME_LEFT, lambda rng: dict(grace=rng.choice([10, 20, 50, 100]))),
    Template("days_in_month", DAYS_IN_MONTH),
    Template(
        "pack_bits", PACK_BITS, lambda rng: dict(parity=rng.randint(0, 1), pmask=rng.choice(["0100", "8000", "0200"]))
    ),
]
