"""An emulated digital I/O terminal pair (EL1008 inputs + EL2008 outputs in one slave).

No mailbox, like the real terminals; the small object dictionary exists only so that the base
class derives the process-data layouts from it: 0x7000:01..n are the outputs (RxPDO 0x1600),
0x6000:01..n the inputs (TxPDO 0x1A00), one bit each, padded to a whole byte.
"""

from __future__ import annotations

from .base import Device


def _padded(words: list, bits: int) -> list:
    if bits % 8:
        words.append((0, 0, 8 - bits % 8))
    return words


class DigitalIO(Device):
    vendor_id = 0x00000002
    product_code = 0x07D83052
    revision = 0x00100000
    name = "EL2008"
    group = "DigIO"
    has_mailbox = False

    def __init__(
        self,
        name: str = "",
        n_inputs: int = 8,
        n_outputs: int = 8,
        *,
        vendor_id: int | None = None,
        product_code: int | None = None,
    ):
        if not (0 <= n_inputs <= 255 and 0 <= n_outputs <= 255):
            raise ValueError("n_inputs and n_outputs must be 0..255")
        if vendor_id is not None:
            self.vendor_id = vendor_id
        if product_code is not None:
            self.product_code = product_code
        super().__init__(name)
        self.n_inputs, self.n_outputs = n_inputs, n_outputs
        od = self.od
        od[0x1000] = 0x00001389  # ETG.5001 modular device profile
        od.add(0x6000, 0, "Inputs", "USINT", n_inputs, "ro")
        for i in range(1, n_inputs + 1):
            od.add(0x6000, i, f"Input {i}", "BOOL", False, "ro", pdo=True)
        od.add(0x7000, 0, "Outputs", "USINT", n_outputs, "ro")
        for i in range(1, n_outputs + 1):
            od.add(0x7000, i, f"Output {i}", "BOOL", False, "rw", pdo=True)
        od.add_pdo_mapping(
            0x1600, "RxPDO mapping", _padded([(0x7000, i, 1) for i in range(1, n_outputs + 1)], n_outputs)
        )
        od.add_pdo_mapping(0x1A00, "TxPDO mapping", _padded([(0x6000, i, 1) for i in range(1, n_inputs + 1)], n_inputs))
        od.add_assignment(self.rx_assign, "RxPDO assign", [0x1600] if n_outputs else [])
        od.add_assignment(self.tx_assign, "TxPDO assign", [0x1A00] if n_inputs else [])

    def set_input(self, i: int, value: bool) -> None:
        """Set input channel i (0-based; channel i + 1 of the terminal, object 0x6000:i+1)."""
        if not 0 <= i < self.n_inputs:
            raise IndexError(f"input {i} out of range 0..{self.n_inputs - 1}")
        self.od[(0x6000, i + 1)] = bool(value)

    def set_inputs(self, values) -> None:
        for i, v in enumerate(values):
            self.set_input(i, v)

    @property
    def inputs(self) -> list:
        return [bool(self.od[(0x6000, i)]) for i in range(1, self.n_inputs + 1)]

    @property
    def outputs(self) -> list:
        """The output channels as last written by the master (0-based list)."""
        return [bool(self.od[(0x7000, i)]) for i in range(1, self.n_outputs + 1)]
