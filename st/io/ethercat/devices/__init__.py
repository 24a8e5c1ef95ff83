"""Emulated EtherCAT slave applications: a CiA 402 servo drive with its motor, digital I/O."""

from .base import Device
from .cia402 import CiA402Drive, State
from .dio import DigitalIO
from .motor import MotorModel, MotorParams

__all__ = ["Device", "CiA402Drive", "State", "DigitalIO", "MotorModel", "MotorParams"]
