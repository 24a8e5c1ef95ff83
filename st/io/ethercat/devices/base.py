"""The application side of an emulated slave: identity, object dictionary, process data, physics.

The slave controller (`esc.py`) owns registers, SyncManagers and the AL state machine; it asks
its `Device` whether a state change is allowed, hands it the received RxPDO image and takes the
TxPDO image from it. Process data lives in the object dictionary: an RxPDO write stores the
mapped entries, `on_outputs()` reacts, `step()` advances the physics on the segment's clock and
updates the entries a TxPDO read then packs.
"""

from __future__ import annotations

from ..od import ObjectDictionary
from ..pdo import PdoLayout

# AL status codes (ETG.1000.6)
AL_OK = 0x0000
AL_INVALID_STATE_CHANGE = 0x0011
AL_UNKNOWN_STATE = 0x0012
AL_BOOTSTRAP_UNSUPPORTED = 0x0013
AL_INVALID_MAILBOX_CONFIG = 0x0016
AL_INVALID_SM_CONFIG = 0x0017
AL_INVALID_OUTPUT_CONFIG = 0x001D
AL_INVALID_INPUT_CONFIG = 0x001E
AL_SYNC_WATCHDOG = 0x001B
AL_DC_INVALID_SYNC = 0x0030
AL_DC_SYNC0_CYCLE = 0x0035


class Device:
    vendor_id = 0
    product_code = 0
    revision = 1
    serial = 0
    name = "device"
    group = "Device"
    has_mailbox = True
    rx_assign, tx_assign = 0x1C12, 0x1C13

    def __init__(self, name: str = ""):
        self.name = name or self.name
        self.od = ObjectDictionary()
        self.od.add(0x1000, 0, "Device type", "UDINT", 0, "ro")
        self.od.add(0x1008, 0, "Device name", "STRING", self.name, "ro", size=len(self.name))
        self.od.add(0x1018, 0, "Identity", "USINT", 4, "ro")
        for sub, (n, v) in enumerate(
            (
                ("Vendor ID", self.vendor_id),
                ("Product code", self.product_code),
                ("Revision", self.revision),
                ("Serial number", self.serial),
            ),
            1,
        ):
            self.od.add(0x1018, sub, n, "UDINT", v, "ro")
        # SyncManager communication types: 0/1 mailbox out/in, 2/3 process data out/in
        self.od.add_record(0x1C00, "Sync manager type", [(f"SM{k}", "USINT", k + 1) for k in range(4)], "ro")
        self.emergencies: list = []  # (error code, error register, 5 bytes) waiting for the mailbox
        self._rx: PdoLayout | None = None
        self._tx: PdoLayout | None = None
        # (the entries a layout maps in its order, its unpack or pack): what a cycle needs of it
        self._rx_plan: tuple | None = None
        self._tx_plan: tuple | None = None

    # ------------------------------------------------------------------ process data
    @property
    def rx_layout(self) -> PdoLayout:
        if self._rx is None:
            self._rx = PdoLayout.from_od(self.od, self.rx_assign) if self.od.has(self.rx_assign) else PdoLayout([])
            self._rx_plan = None
        return self._rx

    @property
    def tx_layout(self) -> PdoLayout:
        if self._tx is None:
            self._tx = PdoLayout.from_od(self.od, self.tx_assign) if self.od.has(self.tx_assign) else PdoLayout([])
            self._tx_plan = None
        return self._tx

    def remap(self) -> None:
        """Forget the layouts (the master changed 0x1C12/0x1C13 or a mapping object)."""
        self._rx = self._tx = None
        self._rx_plan = self._tx_plan = None

    def write_outputs(self, data: bytes) -> None:
        plan = self._rx_plan
        if plan is None:
            lay = self.rx_layout
            plan = self._rx_plan = ([self.od.entries[e.key] for e in lay.data_entries], lay.unpacker())
        entries, unpack = plan
        for e, v in zip(entries, unpack(data)):
            e.value = v
        self.od.writes += 1
        self.on_outputs()

    def read_inputs(self) -> bytes:
        plan = self._tx_plan
        if plan is None:
            lay = self.tx_layout
            plan = self._tx_plan = ([self.od.entries[e.key] for e in lay.data_entries], lay.pack)
        entries, pack = plan
        return pack([e.value for e in entries])

    # ------------------------------------------------------------------ hooks
    def check_transition(self, old: str, new: str) -> int:
        """An AL status code refusing old → new, or AL_OK. PREOP → SAFEOP checks the mapping."""
        if new in ("SAFEOP", "OP") and old in ("PREOP", "INIT"):
            self.remap()
            try:
                _ = (self.rx_layout, self.tx_layout)  # both layouts must be computable
            except (KeyError, TypeError):
                return AL_INVALID_OUTPUT_CONFIG
        return AL_OK

    def on_state(self, old: str, new: str) -> None:
        self.od.state = new

    def on_outputs(self) -> None:
        """New RxPDO values are in the object dictionary."""

    def step(self, t: float, dt: float) -> None:
        """Advance the device's physics to time t (seconds on the segment's clock)."""

    def emergency(self, code: int, register: int = 0, data: bytes = b"") -> None:
        self.emergencies.append((code, register, bytes(data[:5]).ljust(5, b"\0")))
