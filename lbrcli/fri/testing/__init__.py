"""Tools to test FRI clients without a robot: a scripted controller in lock-step with the client (exact states per
cycle, injected faults, an ideal robot that records what it executed) and the judge's figures over a session
(velocity, acceleration and jerk of every command against what the robot executed, how the client left it).

Run your own :class:`~lbrcli.fri.LBRClient` against it::

    from lbrcli.fri import ClientApplication
    from lbrcli.fri.testing import Cycle, ScriptedController, session_script

    app = ClientApplication(MyClient(), "127.0.0.1", 0, bind_host="127.0.0.1", version="1.15",
                            paced_by_replies=True).connect()  # it answers as soon as our reply is in
    ctl = ScriptedController(app.port, session_script(2000), q0).start()
    result = app.run()
    ctl.client_done.set(); ctl.join()
    print(ctl.motion_ratios(limits.velocity, limits.acceleration, limits.jerk), ctl.end_velocity(limits.velocity))
"""

from .scripted import CA, CW, IDLE, MR, MW, Cycle, Reply, ScriptedController, active, preamble, session_script

__all__ = [
    "CA",
    "CW",
    "Cycle",
    "IDLE",
    "MR",
    "MW",
    "Reply",
    "ScriptedController",
    "active",
    "preamble",
    "session_script",
]
