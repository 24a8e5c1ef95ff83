"""The emulated EtherCAT segment: frames, working-counter rules of every command, the AL state
machine with refused transitions, SII, mailbox and SDO, FMMUs, DC and SYNC0, fault injection,
and our FrameMaster bringing it to OP. A minimal CiA 402-shaped device keeps these tests about
the slave controller; the drive model has its own tests."""

import shutil
import struct
import subprocess

import pytest

from st.io.ethercat import wire
from st.io.ethercat.coe import SdoServer, download_request, mbx_frame, parse_response, upload_request
from st.io.ethercat.devices.base import Device
from st.io.ethercat.master import FrameMaster, MasterError
from st.io.ethercat.od import ABORT_NO_OBJECT, ABORT_READ_ONLY, ABORT_STATE, ObjectDictionary, SdoAbort
from st.io.ethercat.pdo import CIA402_RX, CIA402_TX, PdoLayout
from st.io.ethercat.segment import Segment
from st.io.ethercat.sii import crc8
from st.io.ethercat.sii import parse as parse_sii
from st.io.ethercat.wire import (
    APRD,
    APRW,
    APWR,
    ARMW,
    BRD,
    BRW,
    BWR,
    FPRD,
    FPRW,
    FPWR,
    FRMW,
    LRD,
    LRW,
    LWR,
    NOP,
    Datagram,
)


class Echo(Device):
    """CiA 402 process data whose actual position echoes the target; a long OCTETS object."""

    vendor_id, product_code, name = 0x66F, 0x60380004, "echo"

    def __init__(self, name="echo"):
        super().__init__(name)
        od = self.od
        for ix, sx, _bits, dt, n in CIA402_RX + CIA402_TX:
            od.add(
                ix,
                sx,
                n,
                dt,
                0,
                "ro" if ix in (0x6041, 0x6064, 0x606C, 0x603F) else "rw",
                pdo=True,
                writable_in=("PREOP", "SAFEOP", "OP"),
            )
        od.add_pdo_mapping(0x1600, "RxPDO", [(a, b, c) for a, b, c, _, _ in CIA402_RX])
        od.add_pdo_mapping(0x1A00, "TxPDO", [(a, b, c) for a, b, c, _, _ in CIA402_TX])
        od.add_assignment(0x1C12, "RxPDO assign", [0x1600])
        od.add_assignment(0x1C13, "TxPDO assign", [0x1A00])
        od.add(0x2000, 0, "blob", "OCTETS", bytes(range(256)) + bytes(44), size=300)
        self.applied = []  # (t, target) as outputs take effect

    def on_outputs(self):
        self.applied.append((self.t, self.od[0x607A]))

    def step(self, t, dt):
        self.t = t
        self.od[0x6064] = self.od[0x607A]

    t = 0.0


def segment(n=3, **kw):
    return Segment([Echo(f"e{i}") for i in range(n)], **kw)


def send(seg, *dgs, t=0.0):
    out = seg.exchange(wire.encode_frame(list(dgs)), t)
    return wire.decode_frame(out)[2]


def sim_master(seg):
    clock = [0.0]

    def transport(frame):
        clock[0] += 20e-6
        return seg.exchange(frame, clock[0])

    m = FrameMaster(transport, pause=lambda s: clock.__setitem__(0, clock[0] + s), now_ns=lambda: int(clock[0] * 1e9))
    m.clock = clock
    return m


def in_op(n=3, dc_cycle_ns=0):
    seg = segment(n)
    m = sim_master(seg)
    m.scan()
    m.configure(dc_cycle_ns=dc_cycle_ns)
    m.set_state("OP")
    return seg, m


# ---------------------------------------------------------------------------- frames


def test_frame_round_trip_and_wire_format():
    dgs = [Datagram(APRD, 7, 0xFFFF, 0x0130, bytearray(2)), Datagram.logical_dg(LRW, 0x10000, b"\x01\x02\x03")]
    f = wire.encode_frame(dgs)
    assert f[12:14] == b"\x88\xa4" and len(f) == 60  # padded to the Ethernet minimum
    assert struct.unpack_from("<H", f, 14)[0] == (12 + 2 + 12 + 3) | 0x1000  # length 29, type 1
    assert f[16:18] == bytes([APRD, 7]) and struct.unpack_from("<H", f, 20)[0] == 0x0130
    assert struct.unpack_from("<H", f, 22)[0] == 0x8002  # length 2, more follow
    _, _, back = wire.decode_frame(f)
    assert [(d.cmd, d.idx, len(d.data)) for d in back] == [(APRD, 7, 2), (LRW, 0, 3)]
    assert back[1].logical == 0x10000
    with pytest.raises(wire.FrameError, match="not EtherCAT"):
        wire.decode_frame(bytes(12) + b"\x08\x00" + bytes(46))
    with pytest.raises(wire.FrameError, match="header truncated at byte 14"):
        wire.decode_frame(f[:14] + struct.pack("<H", 20 | 0x1000) + f[16:40])
    with pytest.raises(wire.FrameError, match="runs past the EtherCAT length 13"):
        wire.decode_frame(f[:14] + struct.pack("<H", 13 | 0x1000) + f[16:40])


def test_the_returned_frame_is_marked_and_unpadded_frames_are_accepted():
    seg = segment(1)
    f = wire.encode_frame([Datagram(BRD, 0, 0, 0, bytearray(2))], pad=False)
    assert len(f) < 60
    out = seg.exchange(f, 0.0)
    assert out[6] == wire.MASTER_MAC[0] | 0x02 and wire.decode_frame(out)[2][0].wkc == 1


# ---------------------------------------------------------------------------- working counters


def test_working_counters_of_every_register_command():
    seg = segment(3)
    s = seg.slaves
    for i, sl in enumerate(s):  # station addresses 0x1001..
        [d] = send(seg, Datagram(APWR, 0, (-i) & 0xFFFF, 0x0010, bytearray(struct.pack("<H", 0x1001 + i))))
        assert d.wkc == 1 and sl.station == 0x1001 + i
    [d] = send(seg, Datagram(APRD, 0, 0xFFFF, 0x0010, bytearray(2)))  # position 1
    assert d.wkc == 1 and struct.unpack("<H", d.data)[0] == 0x1002 and d.adp == 0x0002
    [d] = send(seg, Datagram(FPRD, 0, 0x1003, 0x0010, bytearray(2)))
    assert d.wkc == 1 and struct.unpack("<H", d.data)[0] == 0x1003
    [d] = send(seg, Datagram(FPRD, 0, 0x2222, 0x0010, bytearray(2)))  # nobody
    assert d.wkc == 0
    [d] = send(seg, Datagram(FPWR, 0, 0x1001, 0x0920, bytearray(b"\x11" * 8)))
    assert d.wkc == 1
    [d] = send(seg, Datagram(FPRW, 0, 0x1001, 0x0920, bytearray(b"\x22" * 8)))
    assert d.wkc == 3 and bytes(d.data) == b"\x11" * 8 and bytes(s[0].mem[0x0920:0x0928]) == b"\x22" * 8
    [d] = send(seg, Datagram(APRW, 0, 0x0000, 0x0920, bytearray(b"\x33" * 8)))
    assert d.wkc == 3 and bytes(d.data) == b"\x22" * 8
    [d] = send(seg, Datagram(BRD, 0, 0, 0x0000, bytearray(1)))
    assert d.wkc == 3 and d.data[0] == 0x11 and d.adp == 3  # broadcasts increment ADP too
    s[1].mem[0x0F80], s[2].mem[0x0F80] = 0x01, 0x04
    [d] = send(seg, Datagram(BRD, 0, 0, 0x0F80, bytearray(1)))  # read-only scratch: ORed
    assert d.data[0] == 0x05
    [d] = send(seg, Datagram(BWR, 0, 0, 0x0928, bytearray(b"\x05\x00\x00\x00")))
    assert d.wkc == 3 and all(x.mem[0x0928] == 5 for x in s)
    # BRW: each slave writes the data as it arrives and ORs what it read into it
    [d] = send(seg, Datagram(BRW, 0, 0, 0x0928, bytearray(b"\x02\x00\x00\x00")))
    assert d.wkc == 9 and d.data[0] == 7 and [x.mem[0x0928] for x in s] == [2, 7, 7]
    [d] = send(seg, Datagram(NOP, 0, 0, 0x0928, bytearray(4)))
    assert d.wkc == 0
    [d] = send(seg, Datagram(APWR, 0, 0xFFFF, 0x0000, bytearray(b"\x99")))  # a read-only register: ignored, counted
    assert d.wkc == 1 and s[1].mem[0] == 0x11


def test_armw_and_frmw_read_at_one_slave_and_write_all_others():
    seg = segment(3)
    for i in range(3):
        send(seg, Datagram(APWR, 0, (-i) & 0xFFFF, 0x0010, bytearray(struct.pack("<H", 0x1001 + i))))
    [d] = send(seg, Datagram(ARMW, 0, 0x0000, 0x0910, bytearray(8)), t=0.5)
    assert d.wkc == 3
    ref = struct.unpack("<Q", d.data)[0]
    assert ref == seg.slaves[0].system_ns(0.5 + seg.d_comm(0))
    [d] = send(seg, Datagram(FRMW, 0, 0x1001, 0x0910, bytearray(8)), t=0.6)
    assert d.wkc == 3
    [d] = send(seg, Datagram(FRMW, 0, 0x7777, 0x0910, bytearray(8)), t=0.6)  # no reference: everybody writes
    assert d.wkc == 3


def test_logical_commands_count_per_fmmu_direction():
    seg, m = in_op(3)
    assert m.expected_wkc == 9 and (m.out_size, m.in_size) == (33, 36)
    img = bytearray(69)
    [d] = send(seg, Datagram.logical_dg(LRW, 0, img), t=0.01)
    assert d.wkc == 9
    [d] = send(seg, Datagram.logical_dg(LRD, 0, bytearray(69)), t=0.01)
    assert d.wkc == 3
    [d] = send(seg, Datagram.logical_dg(LWR, 0, bytearray(69)), t=0.01)
    assert d.wkc == 3
    [d] = send(seg, Datagram.logical_dg(LRW, 33, bytearray(12)), t=0.01)  # only the first slave's inputs
    assert d.wkc == 1
    [d] = send(seg, Datagram.logical_dg(LRW, 5000, bytearray(4)), t=0.01)  # outside every FMMU
    assert d.wkc == 0


def test_process_data_through_the_master():
    seg, m = in_op(2)
    for i in range(2):
        m.write_outputs(i, PdoLayout(CIA402_RX).pack([0x0F, 1000 * (i + 1), 0, 8]))
    assert m.exchange() == 6
    assert m.exchange() == 6
    assert [PdoLayout(CIA402_TX).unpack(m.read_inputs(i))[1] for i in range(2)] == [1000, 2000]


def test_bit_fmmus_merge_into_shared_bytes():
    seg, m = in_op(1)
    s = seg.slaves[0]
    # the input SyncManager's bits 0..2 appear at logical bits 2..4 of byte 100; the others pass
    send(seg, Datagram(FPWR, 0, 0x1001, 0x0620, bytearray(struct.pack("<IHBBHBBB3x", 100, 1, 2, 4, 0x1400, 0, 1, 1))))
    s.device.od[0x6041] = 0b101
    [d] = send(seg, Datagram.logical_dg(LRD, 100, bytearray([0b11100011])), t=0.01)
    assert d.wkc == 1 and d.data[0] == 0b11110111
    # and a bit-wise output: logical bits 5..6 of byte 101 land in bits 3..4 of a RAM byte
    send(seg, Datagram(FPWR, 0, 0x1001, 0x0630, bytearray(struct.pack("<IHBBHBBB3x", 101, 1, 5, 6, 0x1800, 3, 2, 1))))
    s.mem[0x1800] = 0b10000001
    [d] = send(seg, Datagram.logical_dg(LWR, 101, bytearray([0b01000000])), t=0.01)
    assert d.wkc == 1 and s.mem[0x1800] == 0b10010001


# ---------------------------------------------------------------------------- AL states


def al(seg, station, value, t=0.0):
    send(seg, Datagram(FPWR, 0, station, 0x0120, bytearray(struct.pack("<H", value))), t=t)
    [d] = send(seg, Datagram(FPRD, 0, station, 0x0130, bytearray(6)), t=t)
    st, _, code = struct.unpack("<HHH", d.data)
    return st, code


def test_state_machine_refuses_skips_bad_configuration_and_needs_acknowledgement():
    seg = segment(1)
    send(seg, Datagram(APWR, 0, 0, 0x0010, bytearray(b"\x01\x10")))
    assert al(seg, 0x1001, 4) == (0x11, 0x0011)  # INIT → SAFEOP: invalid state change
    assert al(seg, 0x1001, 2) == (0x11, 0x0011)  # still in error: needs the acknowledge bit
    assert al(seg, 0x1001, 0x12) == (0x11, 0x0016)  # PREOP without mailbox SyncManagers
    send(
        seg,
        Datagram(
            FPWR,
            0,
            0x1001,
            0x0800,
            bytearray(
                struct.pack("<HHBBBB", 0x1000, 128, 0x26, 0, 1, 0) + struct.pack("<HHBBBB", 0x1080, 128, 0x22, 0, 1, 0)
            ),
        ),
    )
    assert al(seg, 0x1001, 0x12) == (0x02, 0)
    assert al(seg, 0x1001, 8) == (0x12, 0x0011)  # PREOP → OP: skipping SAFEOP
    send(
        seg,
        Datagram(
            FPWR,
            0,
            0x1001,
            0x0810,
            bytearray(
                struct.pack("<HHBBBB", 0x1100, 10, 0x64, 0, 1, 0) + struct.pack("<HHBBBB", 0x1400, 12, 0x20, 0, 1, 0)
            ),
        ),
    )
    assert al(seg, 0x1001, 0x14) == (0x12, 0x001D)  # output SyncManager 10 bytes, mapping 11
    send(seg, Datagram(FPWR, 0, 0x1001, 0x0812, bytearray(b"\x0b\x00")))
    assert al(seg, 0x1001, 0x14) == (0x04, 0)
    assert al(seg, 0x1001, 3) == (0x14, 0x0013)  # BOOT: not supported
    assert al(seg, 0x1001, 0x15) == (0x14, 0x0012)  # 5: unknown state
    assert al(seg, 0x1001, 0x18) == (0x08, 0)
    assert al(seg, 0x1001, 1) == (0x01, 0)  # down to INIT is always allowed


def test_sync_manager_watchdog_drops_to_safeop_without_outputs():
    seg, m = in_op(1)
    m.clock[0] += 0.001
    assert m.exchange() == 3
    seg.advance(m.clock[0] + 0.099)
    assert seg.slaves[0].state_name == "OP"
    seg.advance(m.clock[0] + 0.1005)
    assert seg.slaves[0].state_name == "SAFEOP"
    assert m.states() == ["SAFEOP+ERR"] and m.slaves[0].al_status_code == 0x001B


# ---------------------------------------------------------------------------- SII


def test_sii_image_checksum_identity_and_categories():
    seg = segment(1)
    s = seg.slaves[0]
    assert crc8(bytes(s.sii[:14])) == s.sii[14]
    info = parse_sii(bytes(s.sii))
    assert (info.vendor_id, info.product_code, info.name) == (0x66F, 0x60380004, "e0")
    assert info.mbx_out == (0x1000, 128) and info.mbx_in == (0x1080, 128) and info.mbx_protocols == 0x0004
    assert [(x.start, x.kind) for x in info.sms] == [(0x1000, 1), (0x1080, 2), (0x1100, 3), (0x1400, 4)]
    assert info.coe_details & 0x20  # complete access
    m = sim_master(seg)
    [found] = m.scan()
    assert (found.vendor_id, found.product_code, found.name, found.mailbox, found.dc) == (
        0x66F,
        0x60380004,
        "e0",
        True,
        True,
    )


# ---------------------------------------------------------------------------- mailbox and SDO


def test_sdo_expedited_normal_segmented_and_complete_access():
    seg, m = in_op(2)
    assert m.sdo_read(1, 0x1018, 1) == struct.pack("<I", 0x66F)
    assert m.sdo_read(1, 0x1008, 0) == b"e1"
    m.sdo_write(0, 0x607A, 0, struct.pack("<i", -5))
    assert m.sdo_read(0, 0x607A, 0) == struct.pack("<i", -5)
    blob = m.sdo_read(0, 0x2000, 0)  # 300 bytes: segmented through 128-byte mailboxes
    assert blob == bytes(range(256)) + bytes(44)
    m.sdo_write(0, 0x2000, 0, bytes(reversed(blob)))  # segmented download
    assert seg.slaves[0].device.od[0x2000] == bytes(reversed(blob))
    ca = m.sdo_read(0, 0x1600, 0, complete=True)
    assert ca == struct.pack("<BxIIII", 4, 0x60400010, 0x607A0020, 0x60FF0020, 0x60600008)
    with pytest.raises(Exception, match="0x06020000"):
        m.sdo_read(0, 0x5555, 0)
    with pytest.raises(Exception, match="0x06010002"):
        m.sdo_write(0, 0x6041, 0, b"\0\0")
    with pytest.raises(Exception, match="0x08000022"):  # mapping objects: PREOP only
        m.sdo_write(0, 0x1C12, 0, b"\0")


def test_mailbox_rules_full_write_and_empty_read_are_not_counted():
    seg, m = in_op(1)
    req = mbx_frame(upload_request(0x1018, 2)).ljust(128, b"\0")
    [d] = send(seg, Datagram(FPRD, 0, 0x1001, 0x1080, bytearray(128)), t=0.01)
    assert d.wkc == 0  # nothing to read
    seg.slaves[0]._set_sm_status(0, True)  # the slave has not taken the last request
    [d] = send(seg, Datagram(FPWR, 0, 0x1001, 0x1000, bytearray(req)), t=0.01)
    assert d.wkc == 0
    seg.slaves[0]._set_sm_status(0, False)
    [d] = send(seg, Datagram(FPWR, 0, 0x1001, 0x1000, bytearray(req)), t=0.01)
    assert d.wkc == 1
    [d] = send(seg, Datagram(FPRD, 0, 0x1001, 0x080D, bytearray(1)), t=0.01)
    assert d.data[0] & 0x08  # the answer waits in SM1
    [d] = send(seg, Datagram(FPRD, 0, 0x1001, 0x1080, bytearray(128)), t=0.01)
    assert d.wkc == 1 and parse_response(bytes(d.data)) == (
        "sdo",
        bytes([0x43]) + struct.pack("<HBI", 0x1018, 2, 0x60380004),
    )
    [d] = send(seg, Datagram(FPRD, 0, 0x1001, 0x1080, bytearray(128)), t=0.01)
    assert d.wkc == 0  # read once: empty again


def test_emergencies_arrive_through_the_mailbox():
    seg, m = in_op(1)
    seg.slaves[0].device.emergency(0x7500, 0x11, b"\x01\x02")
    seg.slaves[0]._fill_mailbox()
    assert m.poll_emergencies(0) == [(0x7500, 0x11, b"\x01\x02\x00\x00\x00")]


def test_sdo_server_codec_directly():
    od = ObjectDictionary()
    od.state = "PREOP"
    od.add(0x3000, 0, "x", "UDINT", 7)
    srv = SdoServer(od, 64)
    req, segs = download_request(0x3000, 0, struct.pack("<I", 9), False, 64)
    assert segs == [] and parse_response(srv.handle(mbx_frame(req))[0])[0] == "sdo" and od[0x3000] == 9
    with pytest.raises(SdoAbort) as e:
        od.download(0x3001, 0, b"\0")
    assert e.value.code == ABORT_NO_OBJECT
    od.add(0x3002, 0, "ro", "UINT", 1, "ro")
    with pytest.raises(SdoAbort) as e:
        od.download(0x3002, 0, b"\0\0")
    assert e.value.code == ABORT_READ_ONLY
    od.add(0x3003, 0, "preop only", "UINT", 1, writable_in=("PREOP",))
    od.state = "OP"
    with pytest.raises(SdoAbort) as e:
        od.download(0x3003, 0, b"\0\0")
    assert e.value.code == ABORT_STATE


# ---------------------------------------------------------------------------- DC


def test_dc_delays_offsets_and_synchronous_outputs():
    seg, m = in_op(3, dc_cycle_ns=1_000_000)
    assert [s.delay_ns for s in m.slaves] == [0, 1005, 2010]  # 1 µs forwarding + 1 m of cable per hop
    # one frame reads every system time: each slave reads when the frame passes it, so the values
    # differ by the propagation, which the delays remove
    t = m.clock[0] + 0.0005
    back = send(seg, *[Datagram(FPRD, 0, 0x1001 + i, 0x0910, bytearray(8)) for i in range(3)], t=t)
    times = [struct.unpack("<Q", d.data)[0] for d in back]
    assert [times[i] - times[0] - m.slaves[i].delay_ns for i in range(3)] == [0, 0, 0]
    # outputs wait for the next SYNC0 pulse: every drive applies them at the same system time
    for dev in (s.device for s in seg.slaves):
        dev.applied.clear()
    for k in range(14):
        m.clock[0] += 0.001
        for i in range(3):
            m.write_outputs(i, PdoLayout(CIA402_RX).pack([0x0F, 100 + k, 0, 8]))
        assert m.exchange() == 9
    first = [seg.slaves[i].device.applied[0] for i in range(3)]
    sys_at = [seg.slaves[i].system_ns(first[i][0]) for i in range(3)]
    assert sys_at[0] == sys_at[1] == sys_at[2] and sys_at[0] % 1_000_000 == 0


# ---------------------------------------------------------------------------- faults


def test_lost_frames_and_a_broken_cable():
    seg, m = in_op(3)
    assert m.exchange() == 9
    seg.drop_frames(2)
    assert [m.exchange(), m.exchange(), m.exchange()] == [-1, -1, 9]
    seg.break_after(0)  # only the first slave answers
    assert m.exchange() == 3
    seg.break_after(None)
    assert m.exchange() == 9


def test_master_reports_a_refused_state_with_the_al_status_code():
    seg = segment(1)
    m = sim_master(seg)
    m.scan()
    m.configure()
    seg.slaves[0].device.check_transition = lambda old, new: 0x001E if new == "OP" else 0
    with pytest.raises(MasterError, match=r"refused OP: it is SAFEOP\+ERR, AL status code 0x001e"):
        m.set_state("OP")


# ---------------------------------------------------------------------------- capture


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("tshark") is None, reason="tshark is not installed (apt install tshark)")
def test_a_capture_decodes_in_tshark_without_malformed_packets(tmp_path):
    seg = segment(2)
    cap = tmp_path / "run.pcap"
    seg.open_capture(str(cap))
    m = sim_master(seg)
    m.scan()
    m.configure(dc_cycle_ns=1_000_000)
    m.set_state("OP")
    m.sdo_read(0, 0x2000, 0)
    for _ in range(20):
        m.clock[0] += 0.001
        m.exchange()
    seg.close()
    out = subprocess.run(
        ["tshark", "-r", str(cap), "-T", "fields", "-e", "_ws.col.Protocol", "-e", "_ws.col.Info"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    lines = out.stdout.splitlines()
    assert len(lines) == 2 * seg.frames and seg.frames > 100
    assert not [x for x in lines if "Malformed" in x]
    assert any(x.startswith("ECAT_MAILBOX") or "CoE" in x or "SDO" in x for x in lines)
    assert any("LRW" in x for x in lines)
