class _st_Totals(_Struct):  # st:14
    __slots__ = ('sum',)  # st:14

    def __init__(self):  # st:14
        self.sum = 0  # st:14

def _fn_Accumulate(x, _r_acc, _r_overflow):  # st:3
    try:  # st:3
        acc = _r_acc.get()  # st:3
        overflow = False  # st:3
        Accumulate = False  # st:3
        overflow = acc > 30000 - x  # st:7
        if not overflow:  # st:8
            acc = (acc + x + 32768 & 65535) - 32768  # st:9
        Accumulate = not overflow  # st:11
        return Accumulate  # st:12
    finally:
        _r_acc.set(acc)  # st:12
        if _r_overflow is not None:  # st:12
            _r_overflow.set(overflow)  # st:12

class _prg_main(_FB):  # st:16
    __slots__ = ('a', 'arr', 't', 'ok', 'ov')  # st:16
    _kinds = ('main',)  # st:16

    def __init__(self):  # st:16
        self.a = 0  # st:17
        self.arr = [0] * 3  # st:17
        self.t = _st_Totals()  # st:17
        self.ok = False  # st:17
        self.ov = False  # st:17

    def _body(self):  # st:16
        ok = self.ok  # st:16
        try:  # st:16
            ok = _fn_Accumulate(5, _AttrRef(self, 'a', (16, True)), _AttrRef(self, 'ov', None))  # st:18
            ok = _fn_Accumulate(2, _ItemRef(self.arr, 1, (16, True)), _AttrRef(self, 'ov', None))  # st:19
            ok = _fn_Accumulate(1, _AttrRef(self.t, 'sum', (16, True)), None)  # st:20
        finally:
            self.ok = ok  # st:21
