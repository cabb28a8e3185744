;This problem was written from a knowledge base snapshot
(define (problem work-cell-order)
(:domain work-cell)
(:objects
    START WS-01 WS-02 SH-01 - location
    M20-100 F20_20_B AXIS-2 - object
    YOUBOT-1 - robot
    PLATFORM-LEFT PLATFORM-RIGHT - platform
)
(:init
    (= (total-cost) 0)
    (robot-at YOUBOT-1 START)
    (gripper-free YOUBOT-1)
    (object-on M20-100 WS-01)
    (object-on F20_20_B WS-01)
    (object-on AXIS-2 SH-01)
)
(:goal (and
    (object-on M20-100 WS-02)
    (object-on F20_20_B WS-02)
    (object-on AXIS-2 WS-01)
    )
)
(:metric minimize (total-cost))
)
