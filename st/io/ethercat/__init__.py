"""EtherCAT process data: an emulated segment (slave controllers, CiA 402 drives, I/O terminals),
masters (`FrameMaster` over the emulated segment or a raw socket, `SoemMaster` through pysoem),
and the scan binding that moves PLCopen axes with CiA 402 drives.

    wire.py     frames and datagrams as on the wire, pcap captures
    esc.py      one slave controller: registers, SII, SyncManagers, FMMUs, AL states, DC
    sii.py      the SII EEPROM image;  coe.py  the CoE mailbox (SDO server and client codec)
    od.py       object dictionaries;  pdo.py  PDO layouts and packing
    devices/    the applications: CiA 402 servo drive with a motor model, digital I/O terminal
    segment.py  a line of slaves with forwarding delays and fault injection
    master.py   the master interface and FrameMaster;  soem.py  the pysoem backend
    serve.py    the emulated segment on a network interface (for SOEM over veth)
    config.py   the segment configuration (TOML);  plan.py  the cycle-time arithmetic;  esi.py  ESI XML
    driver.py   EtherCATDriver: the per-scan exchange, DriveLink: CiA 402 ↔ PLCopen axis
"""

from .config import ConfigError, SegmentConfig
from .config import load as load_segment
from .driver import DriveLink, EtherCATDriver
from .master import FrameMaster, MasterError

__all__ = ["ConfigError", "SegmentConfig", "load_segment", "DriveLink", "EtherCATDriver", "FrameMaster", "MasterError"]
