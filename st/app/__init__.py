"""The application layer: one `st run` composed from the runtime, the I/O drivers, motion and traces.

It sits above every other package (runtime, stdlib, io, api); nothing below imports it.
"""
