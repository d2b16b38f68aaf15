"""The one compiled piece: tracking._rk4, the pendulum integration of tracking.model_look (pyproject.toml holds the
rest). Optional: without a C compiler the install goes on and model_look runs its pure-Python integration."""

from setuptools import Extension, setup

setup(
    ext_modules=[
        Extension(
            "tracking._rk4",
            ["tracking/_rk4.c"],
            optional=True,
            # no fused multiply-add: the results stay equal to the pure-Python fallback's to the last bit
            extra_compile_args=["-O2", "-ffp-contract=off"],
        )
    ]
)
