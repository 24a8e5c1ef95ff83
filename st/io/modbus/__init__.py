"""Modbus TCP slave for HMIs: OpenPLC's address map, a map file for any variable, a server process."""

from .addressmap import MapError, effective_map, load_map
from .slave import ModbusSlave, parse_endpoint, parse_ranges

__all__ = ["ModbusSlave", "MapError", "effective_map", "load_map", "parse_endpoint", "parse_ranges"]
