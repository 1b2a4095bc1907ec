"""Robot models: specifications, validation, Pinocchio building, and the seed catalog."""

from legcore.robots.build import build_any_robot, build_robot, dh_transform, parse_robot_spec
from legcore.robots.legged import Leg, LeggedRobot
from legcore.robots.model import Chain, MotorArrays, Robot
from legcore.robots.spec import (
    DHJoint,
    DHRobotSpec,
    LegSpec,
    MotorSpec,
    RobotSpec,
    URDFRobotSpec,
)

__all__ = [
    "Chain",
    "DHJoint",
    "DHRobotSpec",
    "Leg",
    "LegSpec",
    "LeggedRobot",
    "MotorArrays",
    "MotorSpec",
    "Robot",
    "RobotSpec",
    "URDFRobotSpec",
    "build_any_robot",
    "build_robot",
    "dh_transform",
    "parse_robot_spec",
]
