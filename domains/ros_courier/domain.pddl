; A courier robot whose every action runs on a ROS 2 server (robot.py, in its own
; process): skills.toml binds each action to an action, a service or a topic.
(define (domain ros-courier)
  (:requirements :strips :typing)
  (:types robot place parcel)
  (:predicates
    (at ?r - robot ?p - place)
    (lost ?r - robot)
    (localized ?r - robot)
    (road ?from - place ?to - place)
    (parcel-at ?x - parcel ?p - place)
    (carrying ?r - robot ?x - parcel)
    (empty-handed ?r - robot)
    (addressed-to ?x - parcel ?p - place)
    (delivered ?x - parcel))

  ; tell the robot where it stands (a service with a pose from poses.yaml)
  (:action localize
    :parameters (?r - robot ?p - place)
    :precondition (and (at ?r ?p) (lost ?r))
    :effect (and (localized ?r) (not (lost ?r))))

  ; drive along a road (an action: goal, feedback, cancel)
  (:action drive
    :parameters (?r - robot ?from - place ?to - place)
    :precondition (and (at ?r ?from) (localized ?r) (road ?from ?to))
    :effect (and (at ?r ?to) (not (at ?r ?from))))

  ; close the gripper on a parcel (a service)
  (:action pick-up
    :parameters (?r - robot ?x - parcel ?p - place)
    :precondition (and (at ?r ?p) (parcel-at ?x ?p) (empty-handed ?r))
    :effect (and (carrying ?r ?x) (not (parcel-at ?x ?p)) (not (empty-handed ?r))))

  ; open the gripper (a hand-written ServiceState: legacy_states.py)
  (:action drop
    :parameters (?r - robot ?x - parcel ?p - place)
    :precondition (and (at ?r ?p) (carrying ?r ?x))
    :effect (and (parcel-at ?x ?p) (empty-handed ?r) (not (carrying ?r ?x))))

  ; wait for the receipt of the place (a topic)
  (:action confirm-delivery
    :parameters (?r - robot ?x - parcel ?p - place)
    :precondition (and (at ?r ?p) (parcel-at ?x ?p) (addressed-to ?x ?p))
    :effect (delivered ?x)))
