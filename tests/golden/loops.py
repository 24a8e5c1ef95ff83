class _prg_main(_FB):  # st:3
    __slots__ = ('i', 'k', 'step', 'total', 'n')  # st:3
    _kinds = ('main',)  # st:3

    def __init__(self):  # st:3
        self.i = 0  # st:4
        self.k = 0  # st:4
        self.step = 0  # st:4
        self.total = 0  # st:4
        self.n = 0  # st:4

    def _body(self):  # st:3
        i = self.i  # st:3
        k = self.k  # st:3
        n = self.n  # st:3
        step = self.step  # st:3
        total = self.total  # st:3
        try:  # st:3
            step = 2  # st:5
            i = 1 - 1  # st:6
            for i in _range(1, 11):  # st:6
                if _wd_armed:  # st:6
                    _wd_check()  # st:6
                total = (total + i + 2147483648 & 4294967295) - 2147483648  # st:7
            else:
                i = (i + 1 + 2147483648 & 4294967295) - 2147483648  # st:6
            _t1 = -step  # st:9
            i = 10 - _t1  # st:9
            for i in _range(10, 0 + _for_dir(_t1), _t1):  # st:9
                if _wd_armed:  # st:9
                    _wd_check()  # st:9
                total = (total - 1 + 2147483648 & 4294967295) - 2147483648  # st:10
            else:
                i = (i + _t1 + 2147483648 & 4294967295) - 2147483648  # st:9
            _t2 = 100  # st:12
            k = 1  # st:12
            _t3 = True  # st:12
            while True:  # st:12
                if _wd_armed:  # st:12
                    _wd_check()  # st:12
                if _t3:  # st:12
                    _t3 = False  # st:12
                else:
                    k = (k + 1 + 2147483648 & 4294967295) - 2147483648  # st:12
                if not k <= _t2:  # st:12
                    break  # st:12
                k = (k * 2 + 2147483648 & 4294967295) - 2147483648  # st:13
            while n < 5:  # st:15
                if _wd_armed:  # st:15
                    _wd_check()  # st:15
                n = (n + 1 + 32768 & 65535) - 32768  # st:16
                if n == 3:  # st:17
                    continue  # st:17
                total = (total + n + 2147483648 & 4294967295) - 2147483648  # st:18
            _t4 = True  # st:20
            while _t4 or not n <= 0:  # st:20
                if _wd_armed:  # st:20
                    _wd_check()  # st:20
                _t4 = False  # st:20
                n = (n - 1 + 32768 & 65535) - 32768  # st:21
                if n == 2:  # st:22
                    continue  # st:22
            while True:  # st:24
                if _wd_armed:  # st:24
                    _wd_check()  # st:24
                n = (n + 1 + 32768 & 65535) - 32768  # st:25
                if n >= 3:  # st:26
                    break  # st:26
        finally:
            self.i = i  # st:27
            self.k = k  # st:27
            self.n = n  # st:27
            self.step = step  # st:27
            self.total = total  # st:27
