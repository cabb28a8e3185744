; A courier robot with a battery fetches parcels through a fire door that a second
; robot must hold open while the courier passes (two durative actions that must
; overlap). Battery, distances, speeds and the count of deliveries are numbers.
(define (domain timed-courier)
  (:requirements :strips :typing :durative-actions :duration-inequalities :numeric-fluents)
  (:types robot room parcel)
  (:predicates
    (at ?r - robot ?x - room)
    (parcel-at ?p - parcel ?x - room)
    (carries ?r - robot ?p - parcel)
    (gripper-free ?r - robot)
    (corridor ?a ?b - room)
    (fire-door ?a ?b - room)
    (door-held ?a ?b - room)
    (charging-pad ?x - room))
  (:functions
    (charge-level ?r - robot)
    (capacity ?r - robot)
    (metres ?a ?b - room)
    (speed ?r - robot)
    (delivered))

  (:durative-action drive
    :parameters (?r - robot ?a ?b - room)
    :duration (= ?duration (/ (metres ?a ?b) (speed ?r)))
    :condition (and (at start (at ?r ?a))
                    (at start (>= (charge-level ?r) (metres ?a ?b)))
                    (over all (corridor ?a ?b)))
    :effect (and (at start (not (at ?r ?a)))
                 (at end (at ?r ?b))
                 (at end (decrease (charge-level ?r) (metres ?a ?b)))))

  (:durative-action pass-door
    :parameters (?r - robot ?a ?b - room)
    :duration (= ?duration 3)
    :condition (and (at start (at ?r ?a))
                    (at start (>= (charge-level ?r) (metres ?a ?b)))
                    (over all (fire-door ?a ?b))
                    (over all (door-held ?a ?b)))
    :effect (and (at start (not (at ?r ?a)))
                 (at end (at ?r ?b))
                 (at end (decrease (charge-level ?r) (metres ?a ?b)))))

  (:durative-action hold-door
    :parameters (?r - robot ?a ?b - room)
    :duration (= ?duration 5)
    :condition (and (over all (at ?r ?a)) (at start (fire-door ?a ?b)))
    :effect (and (at start (door-held ?a ?b)) (at start (door-held ?b ?a))
                 (at end (not (door-held ?a ?b))) (at end (not (door-held ?b ?a)))))

  (:durative-action recharge
    :parameters (?r - robot ?x - room)
    :duration (and (>= ?duration 2) (<= ?duration 8))
    :condition (and (at start (charging-pad ?x)) (over all (at ?r ?x)))
    :effect (at end (assign (charge-level ?r) (capacity ?r))))

  (:durative-action grab
    :parameters (?r - robot ?p - parcel ?x - room)
    :duration (= ?duration 2)
    :condition (and (over all (at ?r ?x)) (at start (parcel-at ?p ?x)) (at start (gripper-free ?r)))
    :effect (and (at start (not (parcel-at ?p ?x))) (at start (not (gripper-free ?r)))
                 (at end (carries ?r ?p))))

  (:durative-action hand-over
    :parameters (?r - robot ?p - parcel ?x - room)
    :duration (= ?duration 2)
    :condition (and (over all (at ?r ?x)) (at start (carries ?r ?p)))
    :effect (and (at end (not (carries ?r ?p))) (at end (gripper-free ?r))
                 (at end (parcel-at ?p ?x)) (at end (increase (delivered) 1))))
)
