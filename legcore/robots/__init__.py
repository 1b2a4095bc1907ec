"""Robot models: specifications, validation, Pinocchio building, and the seed catalog."""

from legcore.robots.build import build_robot, dh_transform, parse_robot_spec
from legcore.robots.legged import Leg, LeggedRobot
from legcore.robots.model import Chain, MotorArrays, Robot
from legcore.robots.spec import DHJoint, DHRobotSpec, MotorSpec, RobotSpec, URDFRobotSpec

__all__ = [
    "Chain",
    "DHJoint",
    "DHRobotSpec",
    "Leg",
    "LeggedRobot",
    "MotorArrays",
    "MotorSpec",
    "Robot",
    "RobotSpec",
    "URDFRobotSpec",
    "build_robot",
    "dh_transform",
    "parse_robot_spec",
]
