"""Tests of the demo robot system, examples/robot/robot.lnc, as the README runs it."""
