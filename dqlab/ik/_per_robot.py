"""What the UR solvers compute once per robot (a robot's links are immutable): its kind, its
closed form's parameters."""


def remembered(cache, robot, compute):
    """``compute(robot)``, computed once per robot and kept in the weak-key dictionary
    ``cache``. A ValueError that ``compute`` returns is kept too, and raised (again) as a
    ValueError; a robot that cannot be weakly referenced is computed at each call."""
    try:
        value = cache[robot]
    except (KeyError, TypeError):
        value = compute(robot)
        try:
            cache[robot] = value
        except TypeError:
            pass
    if isinstance(value, ValueError):
        raise ValueError(str(value))
    return value
