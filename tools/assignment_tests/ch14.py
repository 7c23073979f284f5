"""Hidden tests of chapter 14, dynamics with dual quaternions."""


from dqlab_grading import agrees, hidden

import dqlab
from dqlab import dynamics


def _joints(rng):
    return (rng.uniform(-7, 7, 6),)


@hidden("ch14-ex1")
def my_mass_matrix_by_columns(my_mass_matrix):
    """my_mass_matrix builds M(q) from inverse dynamics, column by column, not mass_matrix"""
    ur3 = dqlab.models.ur3()
    agrees(my_mass_matrix, lambda q: dynamics.mass_matrix(ur3, q), _joints, n=10, seed=1401,
           atol=1e-12, forbid=("dqlab.dynamics.mass_matrix",),
           require=("dqlab.dynamics.inverse_dynamics",))


@hidden("ch14-ex2")
def joint1_inertia_by_the_parallel_axis_theorem(joint1_inertia):
    """joint1_inertia sums the links' inertias about the base axis itself, not from M(q)"""
    ur3 = dqlab.models.ur3()
    agrees(joint1_inertia, lambda q: dynamics.mass_matrix(ur3, q)[0, 0], _joints, n=20,
           seed=1402, atol=1e-12,
           forbid=("dqlab.dynamics.mass_matrix", "dqlab.dynamics.inverse_dynamics"))


@hidden("ch14-ex3")
def payload_torques_by_virtual_work(payload_torques):
    """payload_torques is J_v^T (-m g), not a difference of dqlab's gravity torques"""
    ur3 = dqlab.models.ur3()

    def reference(q, m):
        return (dynamics.gravity_torques(dynamics.with_payload(ur3, m), q)
                - dynamics.gravity_torques(ur3, q))
    agrees(payload_torques, reference, lambda rng: (rng.uniform(-7, 7, 6), rng.uniform(0, 5)),
           n=20, seed=1403, atol=1e-12, forbid=("dqlab.dynamics",))


@hidden("ch14-ex4")
def two_link_torques_from_the_textbook(two_link_torques, two_link):
    """two_link_torques evaluates the textbook's equations itself, not inverse_dynamics"""
    agrees(two_link_torques, lambda q, qd, qdd: dynamics.inverse_dynamics(two_link, q, qd, qdd),
           lambda rng: tuple(rng.uniform(-5, 5, size=(3, 2))), n=50, seed=1404, atol=1e-9,
           forbid=("dqlab",))
