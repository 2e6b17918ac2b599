"""Contacts: detection, kinematics, the contact element, joints and friction laws."""

from dda.contact.barton import BartonBandis
from dda.contact.element import ContactElement
from dda.contact.friction import (
    CoulombSingle,
    FrictionLaw,
    FrictionTrial,
    StaticDynamicTransition,
)
from dda.contact.joint import JointMaterial

__all__ = [
    "BartonBandis",
    "ContactElement",
    "CoulombSingle",
    "FrictionLaw",
    "FrictionTrial",
    "JointMaterial",
    "StaticDynamicTransition",
]
