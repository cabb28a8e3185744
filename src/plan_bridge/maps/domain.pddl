; Mobile robots on a map (plan_bridge.maps): the task level of a building. The problem
; is generated from a world's map, the belief and a goal (plan_bridge/maps/tasks.py);
; goals use pyrobosim's task-planning vocabulary (At, Holding, HandEmpty, IsOpen,
; IsLocked, Has) with the world's names.
;
; Spots are the places a task needs: where the robots are, where the objects of the
; goal lie and go, chargers, and the doorways of hallways that are closed but may be
; opened. Two spots joined by a route over open hallways are one navigate apart (its
; duration is the route's length over the robot's speed, the route is the map's: the
; skill drives it); a closed hallway is crossed from one doorway to the other once a
; robot has opened it. Driving drains the battery by (drain-per-metre ?r) per metre;
; chargers recharge it: a robot is (charged ?r) from a charge until it drives again (a
; mission of orders sends a robot low on battery to charge with this goal). Gates open, close and lock: hallways (hall) and pyrobosim
; locations (fixture).
(define (domain robosim)
  (:requirements :strips :typing :durative-actions :numeric-fluents)
  (:types
    bot item - thing
    hall fixture - gate
    spot)
  (:predicates
    (At ?x - thing ?s - spot)
    (Holding ?r - bot ?o - item)
    (HandEmpty ?r - bot)
    (IsOpen ?g - gate)
    (IsLocked ?g - gate)
    (Has ?l - fixture ?o - item)
    (Searched ?s - spot)
    (absent ?o - item ?s - spot)
    (may-hold ?s - spot ?o - item)
    (bot-ready ?r - bot)
    (route ?a ?b - spot)
    (hall-ends ?a ?b - spot ?h - hall)
    (spawn-of ?s - spot ?l - fixture)
    (reaches-gate ?s - spot ?g - gate)
    (is-charger ?l - fixture)
    (charged ?r - bot))
  (:functions
    (battery-level ?r - bot)
    (drain-per-metre ?r - bot)
    (top-speed ?r - bot)
    (metres ?a ?b - spot))

  (:durative-action navigate
    :parameters (?r - bot ?from ?to - spot)
    :duration (= ?duration (/ (metres ?from ?to) (top-speed ?r)))
    :condition (and (at start (bot-ready ?r))
                    (at start (At ?r ?from))
                    (at start (route ?from ?to))
                    (at start (>= (battery-level ?r) (* (drain-per-metre ?r) (metres ?from ?to)))))
    :effect (and (at start (not (bot-ready ?r)))
                 (at start (not (At ?r ?from)))
                 (at start (not (charged ?r)))
                 (at end (At ?r ?to))
                 (at end (bot-ready ?r))
                 (at end (decrease (battery-level ?r) (* (drain-per-metre ?r) (metres ?from ?to))))))

  (:durative-action cross
    :parameters (?r - bot ?from ?to - spot ?h - hall)
    :duration (= ?duration (/ (metres ?from ?to) (top-speed ?r)))
    :condition (and (at start (bot-ready ?r))
                    (at start (At ?r ?from))
                    (at start (hall-ends ?from ?to ?h))
                    (over all (IsOpen ?h))
                    (at start (>= (battery-level ?r) (* (drain-per-metre ?r) (metres ?from ?to)))))
    :effect (and (at start (not (bot-ready ?r)))
                 (at start (not (At ?r ?from)))
                 (at start (not (charged ?r)))
                 (at end (At ?r ?to))
                 (at end (bot-ready ?r))
                 (at end (decrease (battery-level ?r) (* (drain-per-metre ?r) (metres ?from ?to))))))

  (:durative-action pick
    :parameters (?r - bot ?o - item ?s - spot ?l - fixture)
    :duration (= ?duration 2)
    :condition (and (at start (bot-ready ?r))
                    (over all (At ?r ?s))
                    (at start (At ?o ?s))
                    (at start (spawn-of ?s ?l))
                    (over all (IsOpen ?l))
                    (at start (HandEmpty ?r))
                    (at start (> (battery-level ?r) 0)))
    :effect (and (at start (not (bot-ready ?r)))
                 (at start (not (HandEmpty ?r)))
                 (at start (not (At ?o ?s)))
                 (at start (not (Has ?l ?o)))
                 (at end (Holding ?r ?o))
                 (at end (bot-ready ?r))))

  (:durative-action place
    :parameters (?r - bot ?o - item ?s - spot ?l - fixture)
    :duration (= ?duration 2)
    :condition (and (at start (bot-ready ?r))
                    (over all (At ?r ?s))
                    (at start (Holding ?r ?o))
                    (at start (spawn-of ?s ?l))
                    (over all (IsOpen ?l))
                    (at start (> (battery-level ?r) 0)))
    :effect (and (at start (not (bot-ready ?r)))
                 (at start (not (Holding ?r ?o)))
                 (at end (At ?o ?s))
                 (at end (Has ?l ?o))
                 (at end (HandEmpty ?r))
                 (at end (bot-ready ?r))))

  (:durative-action open
    :parameters (?r - bot ?g - gate ?s - spot)
    :duration (= ?duration 3)
    :condition (and (at start (bot-ready ?r))
                    (over all (At ?r ?s))
                    (at start (reaches-gate ?s ?g))
                    (at start (HandEmpty ?r))
                    (over all (not (IsLocked ?g)))
                    (at start (> (battery-level ?r) 0)))
    :effect (and (at start (not (bot-ready ?r)))
                 (at end (IsOpen ?g))
                 (at end (bot-ready ?r))))

  (:durative-action close
    :parameters (?r - bot ?g - gate ?s - spot)
    :duration (= ?duration 3)
    :condition (and (at start (bot-ready ?r))
                    (over all (At ?r ?s))
                    (at start (reaches-gate ?s ?g))
                    (at start (HandEmpty ?r))
                    (over all (not (IsLocked ?g)))
                    (at start (> (battery-level ?r) 0)))
    :effect (and (at start (not (bot-ready ?r)))
                 (at end (not (IsOpen ?g)))
                 (at end (bot-ready ?r))))

  (:durative-action detect
    :parameters (?r - bot ?s - spot ?l - fixture)
    :duration (= ?duration 1)
    :condition (and (at start (bot-ready ?r))
                    (over all (At ?r ?s))
                    (at start (spawn-of ?s ?l))
                    (over all (IsOpen ?l))
                    (at start (> (battery-level ?r) 0)))
    :effect (and (at start (not (bot-ready ?r)))
                 (at end (Searched ?s))
                 (at end (bot-ready ?r))))

  ; An object whose place the belief does not know (it was not where it was believed:
  ; plan_bridge.belief.whereabouts) is looked for at the places it may be in
  ; ((may-hold ?s ?o): the likely places not searched yet, plan_bridge.maps.search).
  ; The plan assumes it is found there; when it is not, the step fails, the belief says
  ; where it is not, and the replan looks at the next place.
  (:durative-action search
    :parameters (?r - bot ?o - item ?s - spot ?l - fixture)
    :duration (= ?duration 1)
    :condition (and (at start (bot-ready ?r))
                    (over all (At ?r ?s))
                    (at start (may-hold ?s ?o))
                    (at start (not (absent ?o ?s)))
                    (at start (spawn-of ?s ?l))
                    (over all (IsOpen ?l))
                    (at start (> (battery-level ?r) 0)))
    :effect (and (at start (not (bot-ready ?r)))
                 (at end (At ?o ?s))
                 (at end (Has ?l ?o))
                 (at end (bot-ready ?r))))

  (:durative-action charge
    :parameters (?r - bot ?s - spot ?l - fixture)
    :duration (= ?duration 10)
    :condition (and (at start (bot-ready ?r))
                    (over all (At ?r ?s))
                    (at start (spawn-of ?s ?l))
                    (at start (is-charger ?l)))
    :effect (and (at start (not (bot-ready ?r)))
                 (at end (assign (battery-level ?r) 100))
                 (at end (charged ?r))
                 (at end (bot-ready ?r)))))
