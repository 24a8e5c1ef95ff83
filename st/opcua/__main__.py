"""The OPC UA server process: `python -m st.opcua`, its configuration pickled on stdin (driver.py)."""

import pickle
import sys

from .server import serve

serve(pickle.loads(sys.stdin.buffer.read()))
