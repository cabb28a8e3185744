#!/usr/bin/env python
# ruff: noqa
"""A Sequence of callback states; imports smach_ros but needs no ROS (ROS 1 era)."""

import smach
import smach_ros


@smach.cb_interface(input_keys=["n"], output_keys=["n"], outcomes=["ok"])
def double(ud):
    ud.n = ud.n * 2
    return "ok"


def main():
    seq = smach.Sequence(
        outcomes=["ok"], connector_outcome="ok", input_keys=["n"], output_keys=["n"]
    )
    seq.set_initial_state(["SECOND"])
    with seq:
        smach.Sequence.add("FIRST", smach.CBState(double))
        smach.Sequence.add("SECOND", smach.CBState(double))
        smach.Sequence.add("THIRD", smach.CBState(double))
    ud = smach.UserData()
    ud.n = 1
    outcome = seq.execute(ud)
    print("outcome: %s n: %d" % (outcome, ud.n))


if __name__ == "__main__":
    main()
