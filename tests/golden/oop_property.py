class _fb_Counter(_FB):  # st:2
    __slots__ = ('count', 'limit__')  # st:2
    _kinds = ('counter',)  # st:2

    def __init__(self):  # st:2
        self.count = 0  # st:3
        self.limit__ = 10  # st:4

    def _body(self):  # st:2
        pass  # st:2

    def _m_Step(self):  # st:9
        Step = False  # st:9
        if self.count < self._pg_Limit():  # st:10
            self.count = (self.count + 1 + 32768 & 65535) - 32768  # st:11
        Step = self.count >= self._pg_Limit()  # st:13
        return Step  # st:14

    def _pg_Limit(self):  # st:6
        Limit = 0  # st:6
        Limit = self.limit__  # st:6
        return Limit  # st:6

    def _ps_Limit(self, Limit):  # st:7
        self.limit__ = Limit  # st:7
        return  # st:7

class _fb_DoubleCounter(_FB):  # st:17
    __slots__ = ('count', 'limit__')  # st:17
    _kinds = ('counter', 'doublecounter')  # st:17

    def __init__(self):  # st:17
        self.count = 0  # st:3
        self.limit__ = 10  # st:4

    def _body(self):  # st:17
        _fb_Counter._body(self)  # st:25

    def _m_Step(self):  # st:22
        Step = False  # st:22
        Step = _fb_Counter._m_Step(self)  # st:23
        return Step  # st:24

    def _pg_Limit(self):  # st:19
        Limit = 0  # st:19
        Limit = (_fb_Counter._pg_Limit(self) * 2 + 32768 & 65535) - 32768  # st:19
        return Limit  # st:19

    def _ps_Limit(self, Limit):  # st:20
        _fb_Counter._ps_Limit(self, Limit)  # st:20
        return  # st:20

class _prg_main(_FB):  # st:28
    __slots__ = ('c', 'full', 'seen')  # st:28
    _kinds = ('main',)  # st:28

    def __init__(self):  # st:28
        self.c = _fb_DoubleCounter()  # st:29
        self.full = False  # st:29
        self.seen = 0  # st:29

    def _body(self):  # st:28
        c = self.c  # st:28
        c._ps_Limit(3)  # st:30
        self.full = c._m_Step()  # st:31
        self.seen = c._pg_Limit()  # st:32
        c._body()  # st:33
