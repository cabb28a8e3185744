; What a knowledge base holds before the mission: objects and facts, no goal yet.
(define (problem tour-kb)
  (:domain waypoint-tour)
  (:objects r1 - robot wp1 wp2 wp3 - waypoint)
  (:init (at r1 dock) (charging r1)
         (linked dock wp1) (linked wp1 dock) (linked wp1 wp2) (linked wp2 wp1)
         (linked wp2 wp3) (linked wp3 wp2) (linked wp3 dock) (linked dock wp3))
  (:goal (and)))
