"""From the lab's raw records to wall motion.

Raw format, channel health, four-DOF kinematics (Eqs. 3-8), validity, the
linearised flight fitted to a record (derivative filter), release and
motion, reduction of one test, and the virtual lab.
"""
