"""The web server process: `python -m st.web`, its configuration pickled on stdin (st/web/link.py)."""

import pickle
import sys

from .server import serve

serve(pickle.loads(sys.stdin.buffer.read()))
