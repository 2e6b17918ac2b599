"""Contacts: detection, kinematics, the contact element, joints and friction laws."""

from dda.contact.barton import BartonBandis
from dda.contact.element import ContactElement
from dda.contact.friction import (
    CoulombLike,
    CoulombSingle,
    FrictionLaw,
    FrictionTrial,
    StaticDynamicTransition,
)
from dda.contact.joint import JointMaterial
from dda.contact.law_check import check_friction_law

__all__ = [
    "BartonBandis",
    "ContactElement",
    "CoulombLike",
    "CoulombSingle",
    "FrictionLaw",
    "FrictionTrial",
    "JointMaterial",
    "StaticDynamicTransition",
    "check_friction_law",
]
