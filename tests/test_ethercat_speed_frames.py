"""The master's process-data frame, encoded once and patched each cycle, is the frame the general
encoder builds; answers of another shape still go through the general decoder."""

from __future__ import annotations

from st.io.ethercat import wire
from st.io.ethercat.config import build_segment, from_dict
from st.io.ethercat.master import FrameMaster
from st.io.ethercat.pdo import CIA402_RX, PdoLayout
from st.io.ethercat.wire import FRMW, LRW, Datagram


def _master(n: int = 2):
    cfg = {"segment": {"cycle": "1ms", "dc": True}, "slave": [{"name": f"d{i}", "type": "cia402"} for i in range(n)]}
    seg = build_segment(from_dict(cfg))
    clock = [0.0]
    sent: list = []
    answers: list = []

    def transport(frame):
        sent.append(frame)
        out = seg.exchange(frame, clock[0])
        answers.append(out)
        return out

    m = FrameMaster(transport, pause=lambda s: clock.__setitem__(0, clock[0] + s), now_ns=lambda: int(clock[0] * 1e9))
    m.scan()
    m.configure(dc_cycle_ns=1_000_000)
    m.set_state("OP")
    return m, clock, sent, answers


def test_the_cyclic_frame_is_the_general_encoding():
    m, clock, sent, answers = _master()
    rx = PdoLayout(CIA402_RX)
    for k in range(300):  # the index wraps past 255
        clock[0] += 0.001
        for i in range(2):
            m.write_outputs(i, rx.pack([0x06 if k < 50 else 0x0F, 7 * k + i, 0, 8]))
        image = bytes(m.image)
        idx = m._idx
        wkc = m.exchange()
        lrw = Datagram.logical_dg(LRW, 0, image, idx=(idx + 1) & 0xFF)
        frmw = Datagram(FRMW, (idx + 2) & 0xFF, m.dc_ref, 0x0910, bytearray(8))
        assert sent[-1] == wire.encode_frame([lrw, frmw])
        _, _, back = wire.decode_frame(answers[-1])
        assert wkc == back[0].wkc == m.expected_wkc
        assert bytes(m.image[m.out_size :]) == bytes(back[0].data[m.out_size :])
        assert m.dc_time == int.from_bytes(back[1].data, "little")


def test_an_answer_of_another_shape_goes_through_the_general_decoder():
    m, clock, sent, answers = _master()
    inner = m.transport

    def vlan(frame):  # the same answer with a VLAN tag: other offsets
        out = inner(frame)
        return out[:12] + b"\x81\x00\x00\x05" + out[12:]

    m.transport = vlan
    clock[0] += 0.001
    assert m.exchange() == m.expected_wkc
    _, _, back = wire.decode_frame(answers[-1])
    assert m.dc_time == int.from_bytes(back[1].data, "little")
    m.transport = lambda frame: b"\x00" * 20  # not EtherCAT: a lost frame
    lost = m.lost
    assert m.exchange() == -1 and m.lost == lost + 1
