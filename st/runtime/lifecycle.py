"""The PLC's states and the transitions between them: STOP, RUN, FAULT.

A fault or a stop puts the outputs to their safe values (FALSE/0, or `safe_outputs`), tells
the I/O drivers (`after_job()` without a task) and commits retained data. A warm restart
builds the program afresh and restores the retained values.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .build import build, install
from .faults import FaultInfo, PLCFaultError, PLCStartError
from .process_image import parse_address
from .retained import commit_retained, restore_retained, retained_values
from .scheduler import reset_releases

if TYPE_CHECKING:
    from .plc import PLC

STOP, RUN, FAULT = "STOP", "RUN", "FAULT"


def fault_error(plc: PLC) -> PLCFaultError:
    """The error for an attempt to run a PLC in FAULT."""
    assert plc.fault is not None  # FAULT is only entered with its FaultInfo
    return PLCFaultError(plc.fault)


def enter_fault(plc: PLC, info: FaultInfo) -> None:
    plc.state = FAULT
    plc.fault = info
    plc.faults.append(info)
    plc.log.add(plc.time, 0x04, str(info))  # in the PLC's log too: the online mode's, st run's
    safe_outputs(plc)
    if plc.retain_store is not None:
        # as a PLC's retain memory: the values as the faulting scan left them, nothing lost
        commit_retained(plc)


def safe_outputs(plc: PLC) -> None:
    """Outputs to their safe values: FALSE/0, or what `safe_outputs` configures."""
    plc.image.clear("Q")
    for addr, v in plc.safe_outputs.items():
        area, size, i = parse_address(addr)
        plc.image.tables[(area, size)][i] = v if size == "X" else int(v)
    for d in plc.io:
        d.after_job()


def stop(plc: PLC) -> None:
    if plc.state == RUN:
        plc.state = STOP
    safe_outputs(plc)
    if plc.retain_store is not None:
        commit_retained(plc)


def start(plc: PLC) -> None:
    if plc.state == FAULT:
        raise fault_error(plc)
    plc.state = RUN
    plc._next_tick = reset_releases(plc.tasks, plc.tick, plc._time)
    for t in plc.tasks:
        for b in t.outs:
            b.publish()


def reset_fault(plc: PLC) -> None:
    plc.state = RUN
    plc.fault = None
    plc._next_tick = reset_releases(plc.tasks, plc.tick, plc._time)


def restart(plc: PLC, cold: bool = False) -> None:
    """Warm restart: fresh instances, retained values restored; a program whose instances fault again
    while being created stays in FAULT (PLCFaultError). Cold: retained values too start from their
    initial values (and the retain file is cleared)."""
    if cold:
        committed = None
        if plc.retain_store is not None:
            plc.retain_store.clear()
    else:
        snapshot = retained_values(plc) if plc.retain_store is None else None
        committed = plc.retain_store.load() if plc.retain_store is not None else snapshot
    try:
        b = build(
            plc.compiled, plc.image, cycle=plc.cycle, watchdog=plc.watchdog, policy=plc.policy_name, what="restart"
        )
    except PLCStartError as e:  # FB_init faults again: stay in FAULT, say why
        info = e.fault or FaultInfo("START", str(e))
        enter_fault(plc, info)
        raise PLCFaultError(info) from None
    plc.fault = None
    plc.state = RUN
    install(plc, b)
    if committed:
        restore_retained(plc, committed)


def close(plc: PLC) -> None:
    stop(plc)
    if plc.retain_store is not None:
        plc.retain_store.close()
        plc.retain_store = None
