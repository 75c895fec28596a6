"""Servo tracking: the humanoid's position servos follow a motion in simulation, root free
or driven along the reference; the plan fed to MuJoCo and the result's figures."""
