# cython: boundscheck=False, wraparound=False, cdivision=True, language_level=3
# bench/workloads/int_arrays.st written by hand as a typed second tier would emit it (issue 20's
# proposal, measured by `bench_tier_cython.py --typed-sketch`): the state in C int32 fields and
# arrays, intermediates in int64 and cast on store (the DINT wrap), C's / and % (truncation toward
# zero, the dividend's sign: IEC's DIV and MOD), no index checks where the FOR range proves the
# index in bounds. A sketch for measuring, not a tier: no watchdog, no fault locations.
from libc.stdint cimport int32_t, int64_t

cdef class Main:
    cdef public int32_t checksum, i, t, s, k, total
    cdef int32_t a[100]
    cdef int32_t b[100]
    def __init__(self):
        cdef int n
        for n in range(100):
            self.a[n] = 0
            self.b[n] = 0
        self.checksum = self.i = self.t = self.s = self.k = self.total = 0
    cpdef body(self):
        cdef int64_t v
        cdef int32_t i
        self.s = 0
        for i in range(0, 100):
            v = <int64_t>self.a[i] + i * 7 + self.k
            self.a[i] = <int32_t>(v % 10007)   # C: truncates toward zero like IEC
        for i in range(0, 99):
            if self.a[i] > self.a[i + 1]:
                self.t = self.a[i]
                self.a[i] = self.a[i + 1]
                self.a[i + 1] = self.t
        for i in range(0, 100):
            self.b[99 - i] = <int32_t>(<int64_t>(self.a[i] / 3) + (self.b[99 - i] % 17))
            v = <int64_t>self.s + <int64_t>self.b[99 - i] * (i + 1)
            self.s = <int32_t>(v % 1000003)
        self.i = 100
        self.k = <int32_t>((self.k + 1) % 101)
        self.total = <int32_t>((<int64_t>self.total + self.s) % 1000003)
        self.checksum = self.total
