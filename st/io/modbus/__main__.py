"""The Modbus server process: `python -m st.io.modbus`, its configuration pickled on stdin."""

import pickle
import sys

from .server import serve

serve(*pickle.loads(sys.stdin.buffer.read()))
