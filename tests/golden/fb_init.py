class _fb_Device(_FB):  # st:2
    __slots__ = ('id', 'started')  # st:2
    _kinds = ('device',)  # st:2

    def __init__(self):  # st:2
        self.id = 0  # st:3
        self.started = False  # st:3

    def _body(self):  # st:2
        pass  # st:2

    def _ctor(self, a):  # st:2
        _fb_Device._m_FB_init(self, True, False, a.get('nid', 1))  # st:2
        return self  # st:2

    def _m_FB_init(self, bInitRetains, bInCopyCode, nId):  # st:4
        FB_init = False  # st:4
        self.id = nId  # st:6
        self.started = bInitRetains & (not bInCopyCode)  # st:7
        return FB_init  # st:8

class _fb_Valve(_FB):  # st:11
    __slots__ = ('id', 'started', 'channel')  # st:11
    _kinds = ('device', 'valve')  # st:11

    def __init__(self):  # st:11
        self.id = 0  # st:3
        self.started = False  # st:3
        self.channel = 0  # st:12

    def _body(self):  # st:11
        pass  # st:11

    def _ctor(self, a):  # st:11
        _fb_Device._m_FB_init(self, True, False, a.get('nid', 1))  # st:11
        _fb_Valve._m_FB_init(self, True, False, a.get('nid', 0))  # st:11
        return self  # st:11

    def _m_FB_init(self, bInitRetains, bInCopyCode, nId):  # st:13
        FB_init = False  # st:13
        self.channel = (nId * 10 + 32768 & 65535) - 32768  # st:15
        return FB_init  # st:16

class _prg_main(_FB):  # st:19
    __slots__ = ('v1', 'v2', 'sum')  # st:19
    _kinds = ('main',)  # st:19

    def __init__(self):  # st:19
        self.v1 = _fb_Valve()._ctor({'nid': 4})  # st:20
        self.v2 = _fb_Valve()._ctor({})  # st:20
        self.sum = 0  # st:20

    def _body(self):  # st:19
        self.sum = (self.v1.id + self.v1.channel + self.v2.id + 32768 & 65535) - 32768  # st:21
