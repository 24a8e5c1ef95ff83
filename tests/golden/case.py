class _prg_main(_FB):  # st:4
    __slots__ = ('code', 'mode', 'out', 'lamp')  # st:4
    _kinds = ('main',)  # st:4

    def __init__(self):  # st:4
        self.code = 0  # st:5
        self.mode = 0  # st:5
        self.out = 0  # st:5
        self.lamp = False  # st:5

    def _body(self):  # st:4
        code = self.code  # st:4
        out = self.out  # st:4
        try:  # st:4
            if code == 0:  # st:7
                out = 0  # st:7
            elif code in {1, 2, 3}:  # st:8
                out = 10  # st:8
            elif 4 <= code <= 9:  # st:9
                out = (code * 2 + 32768 & 65535) - 32768  # st:9
            else:
                out = -1  # st:11
            _t1 = self.mode  # st:13
            if _t1 == 0:  # st:14
                self.lamp = False  # st:14
            elif _t1 in {1, 2}:  # st:15
                self.lamp = True  # st:15
            code = _t2 % 12 if (_t2 := (code + 1)) >= 0 else -(-_t2 % 12)  # st:17
        finally:
            self.code = code  # st:18
            self.out = out  # st:18
