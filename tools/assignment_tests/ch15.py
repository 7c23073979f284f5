"""Hidden tests of chapter 15, simulating the arm."""


from dqlab_grading import agrees, hidden

import dqlab


@hidden("ch15-ex1")
def my_flange_pose_composes_the_bodies(my_flange_pose):
    """my_flange_pose composes the placements and joint turns itself, not with robot.fk"""
    report = dqlab.models.ur3_mdh()
    agrees(my_flange_pose, report.fk, lambda rng: (rng.uniform(-7, 7, 6),), n=20, seed=1501,
           atol=1e-12, forbid=("dqlab.robot.Robot.fk", "dqlab.robot.Robot.fk_dq",
                               "dqlab.robot.Robot.fk_dq_screw"))
