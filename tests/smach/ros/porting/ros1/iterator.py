#!/usr/bin/env python
# ruff: noqa
"""Visit every room of a list with an Iterator (ROS 1 era)."""

import rospy
import smach


@smach.cb_interface(input_keys=["it_data", "visited"], output_keys=["visited"], outcomes=["next"])
def visit(ud):
    rospy.loginfo("visiting %s" % ud.it_data)
    ud.visited = ud.visited + [ud.it_data]
    return "next"


def main():
    rospy.init_node("port_iterator")
    sm = smach.StateMachine(outcomes=["toured"])
    sm.userdata.visited = []
    with sm:
        tour = smach.Iterator(
            outcomes=["toured"],
            input_keys=["visited"],
            output_keys=["visited"],
            it=lambda: ["hall", "lab", "dock"],
            it_label="it_data",
            exhausted_outcome="toured",
        )
        with tour:
            smach.Iterator.set_contained_state(
                "VISIT", smach.CBState(visit), loop_outcomes=["next"]
            )
        smach.StateMachine.add("TOUR", tour, transitions={"toured": "toured"})
    outcome = sm.execute()
    print("outcome: %s visited: %s" % (outcome, ",".join(sm.userdata.visited)))


if __name__ == "__main__":
    main()
