"""The `soem` backend: the same Master interface through pysoem (SOEM) on a network interface.

The path to real drives: needs root (or CAP_NET_RAW) and `pip install pysoem`. The order that
reaches OP (see ../shared/notes/ethercat.md): config_init → PDO assignment over SDO in the
PREOP → SAFEOP hook → config_map → config_dc and SYNC0 per DC slave → SAFEOP → OP while
exchanging process data. pysoem holds the interpreter lock in config_map, config_dc and state
checks, so an emulated segment must be served from another process (`st ethercat serve`).
"""

from __future__ import annotations

import struct

from .master import Master, MasterError, SlaveInfo
from .pdo import KNOWN_NAMES, KNOWN_TYPES, PdoLayout

_STATES = {"INIT": 1, "PREOP": 2, "BOOT": 3, "SAFEOP": 4, "OP": 8}
_NAMES = {v: k for k, v in _STATES.items()}


def available() -> str | None:
    """None when pysoem can be used, else why not."""
    try:
        import pysoem  # noqa: F401
    except ImportError:
        return "pysoem is not installed (pip install pysoem)"
    return None


class SoemMaster(Master):
    def __init__(self, iface: str, frame_timeout_us: int = 2000):
        why = available()
        if why:
            raise MasterError(why)
        import pysoem

        self.pysoem = pysoem
        self.iface = iface
        self.timeout_us = frame_timeout_us
        self.m = pysoem.Master()
        self.slaves: list = []
        self.expected_wkc = 0
        self.dc_time = 0
        self.lost = 0
        self._assign: dict = {}

    def open(self) -> None:
        try:
            self.m.open(self.iface)
        except Exception as e:  # noqa: BLE001 - pysoem raises ConnectionError or its own types
            raise MasterError(f"cannot open {self.iface}: {e} (root or CAP_NET_RAW needed)") from None

    def close(self) -> None:
        try:
            self.m.close()
        except Exception:  # noqa: BLE001
            pass

    def scan(self) -> list:
        n = self.m.config_init()
        if n <= 0:
            raise MasterError(f"no EtherCAT slave answered on {self.iface}")
        self.slaves = []
        for i, s in enumerate(self.m.slaves):
            info = SlaveInfo(i, 0x1001 + i, s.man, s.id, s.rev, 0, s.name, mailbox=True)
            self.slaves.append(info)
        self.states()
        return self.slaves

    def states(self) -> list:
        self.m.read_state()
        out = []
        for info, s in zip(self.slaves, self.m.slaves):
            st = s.state
            info.state = _NAMES.get(st & 0x0F, hex(st)) + ("+ERR" if st & 0x10 else "")
            info.al_status_code = s.al_status
            out.append(info.state)
        return out

    def configure(
        self, pdo_assign: dict | None = None, dc_cycle_ns: int = 0, dc_shift_ns: int = 0, preop_hook=None
    ) -> None:
        assign = pdo_assign or {}
        if preop_hook is not None:  # config_init left the slaves in PREOP
            preop_hook(self)
        for i, s in enumerate(self.m.slaves):
            if i in assign:
                rx, tx = assign[i]

                def setup(pos, rx=rx, tx=tx):
                    sl = self.m.slaves[pos]
                    for idx, pdos in ((0x1C12, rx), (0x1C13, tx)):
                        if pdos is None:
                            continue
                        sl.sdo_write(idx, 0, b"\0")
                        for k, p in enumerate(pdos, 1):
                            sl.sdo_write(idx, k, struct.pack("<H", p))
                        sl.sdo_write(idx, 0, bytes([len(pdos)]))

                s.config_func = setup
        try:
            self.m.config_map()
        except Exception as e:  # noqa: BLE001 - ConfigMapError lists the failing SDOs
            raise MasterError(f"PDO mapping failed: {e}") from None
        self.expected_wkc = self.m.expected_wkc
        if dc_cycle_ns:
            self.m.config_dc()
            for s in self.m.slaves:
                try:
                    s.dc_sync(True, dc_cycle_ns, dc_shift_ns)
                except Exception:  # noqa: BLE001 - a slave without DC
                    pass
        for info, s in zip(self.slaves, self.m.slaves):
            info.out_bytes, info.in_bytes = len(s.output), len(s.input)
            info.rx_layout, info.tx_layout = self._layout(s, 0x1C12), self._layout(s, 0x1C13)
        self.set_state("SAFEOP")

    def _layout(self, s, assign: int) -> PdoLayout:
        items = []
        try:
            n = s.sdo_read(assign, 0)[0]
            for k in range(1, n + 1):
                pdo = struct.unpack("<H", s.sdo_read(assign, k)[:2])[0]
                m = s.sdo_read(pdo, 0)[0]
                for j in range(1, m + 1):
                    w = struct.unpack("<I", s.sdo_read(pdo, j)[:4])[0]
                    ix, sx, bits = w >> 16, (w >> 8) & 0xFF, w & 0xFF
                    dtype = KNOWN_TYPES.get(ix) or {1: "BOOL", 8: "USINT", 16: "UINT", 32: "UDINT"}.get(bits, "OCTETS")
                    items.append(
                        (ix, sx, bits, "PAD" if ix == 0 else dtype, KNOWN_NAMES.get(ix, f"{ix:#06x}:{sx:02x}"))
                    )
        except Exception:  # noqa: BLE001 - no CoE: the raw image only
            return PdoLayout([])
        return PdoLayout(items)

    def set_state(self, state: str, timeout: float = 2.0, slaves=None) -> str:
        code = _STATES[state]
        self.m.state = code
        self.m.write_state()
        loops = max(1, int(timeout / 0.002))
        got = 0
        for _ in range(loops):
            if code == 8:
                self.m.send_processdata()
                self.m.receive_processdata(self.timeout_us)
            got = self.m.state_check(code, 2000)
            if got == code:
                break
        self.states()
        if got != code:
            bad = next((s for s in self.slaves if s.state != state), None)
            raise MasterError(
                f"slave {bad.position if bad else '?'} refused {state}: "
                f"{bad.state if bad else got} (AL status code {bad.al_status_code if bad else 0:#06x})"
            )
        return state

    def exchange(self) -> int:
        self.m.send_processdata()
        wkc = self.m.receive_processdata(self.timeout_us)
        self.dc_time = self.m.dc_time
        if wkc <= 0:
            self.lost += 1
            return -1
        return wkc

    def sdo_read(self, slave: int, index: int, sub: int, complete: bool = False) -> bytes:
        try:
            return bytes(self.m.slaves[slave].sdo_read(index, sub, ca=complete))
        except Exception as e:  # noqa: BLE001
            raise MasterError(f"SDO read {index:#06x}:{sub} of slave {slave}: {e}") from None

    def sdo_write(self, slave: int, index: int, sub: int, data: bytes, complete: bool = False) -> None:
        try:
            self.m.slaves[slave].sdo_write(index, sub, bytes(data), ca=complete)
        except Exception as e:  # noqa: BLE001
            raise MasterError(f"SDO write {index:#06x}:{sub} of slave {slave}: {e}") from None

    def write_outputs(self, slave: int, data: bytes) -> None:
        self.m.slaves[slave].output = bytes(data)

    def read_inputs(self, slave: int) -> bytes:
        return bytes(self.m.slaves[slave].input)

    def poll_emergencies(self, slave: int) -> list:
        return []
