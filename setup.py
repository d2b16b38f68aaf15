"""The compiled pieces (pyproject.toml holds the rest): tracking._rk4, the pendulum integration of
tracking.model_look; planners._planar, the planar pendulum step of the swing-up search; trajectories._quick, the quick
acceptance of a joint command in every FRI cycle (the envelope's and the guard's per-joint comparisons). Optional:
without a C compiler the install goes on and each runs its pure-Python code (equal to the last bit)."""

from setuptools import Extension, setup

setup(
    ext_modules=[
        Extension(
            "tracking._rk4",
            ["tracking/_rk4.c"],
            optional=True,
            # no fused multiply-add: the results stay equal to the pure-Python fallback's to the last bit
            extra_compile_args=["-O2", "-ffp-contract=off"],
        ),
        Extension(
            "planners._planar", ["planners/_planar.c"], optional=True, extra_compile_args=["-O2", "-ffp-contract=off"]
        ),  # fmt: skip
        Extension(
            "trajectories._quick",
            ["trajectories/_quick.c"],
            optional=True,
            extra_compile_args=["-O2", "-ffp-contract=off"],
        ),  # fmt: skip
    ]
)
