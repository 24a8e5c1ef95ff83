"""OPC UA: the PLC's variables for SCADA, MES and HMIs (`st run --opcua`, docs/opcua.md).

symbols.py decides what is published (the symbol configuration), driver.py is the PLC's side
(an I/O driver), server.py the asyncua server in its own process, channel.py their shared
memory, users.py the users file.
"""

from .driver import OpcUaServer

__all__ = ["OpcUaServer"]
