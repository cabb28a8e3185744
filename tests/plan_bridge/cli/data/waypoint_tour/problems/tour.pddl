; The same waypoints with a goal of their own.
(define (problem tour-wp2)
  (:domain waypoint-tour)
  (:objects r1 - robot wp1 wp2 wp3 - waypoint)
  (:init (at r1 dock) (charging r1)
         (linked dock wp1) (linked wp1 dock) (linked wp1 wp2) (linked wp2 wp1)
         (linked wp2 wp3) (linked wp3 wp2) (linked wp3 dock) (linked dock wp3))
  (:goal (and
    (visited wp2))))
