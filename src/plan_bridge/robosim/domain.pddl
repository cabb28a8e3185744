; A mobile manipulator in a pyrobosim world (plan_bridge.robosim). The problem is
; generated from the world file; goals use pyrobosim's task-planning vocabulary
; (At, Holding, HandEmpty, IsOpen, IsLocked, Has) with the world's entity names.
;
; Spots are where a robot can stand: a room's navigation pose (area), an object spawn
; of a location (spawn) and each end of a hallway (door, one per room it joins).
; A robot drives between spots of one room (navigate) and through an open hallway
; from one of its ends to the other (cross); durations are distance / speed, and
; driving drains the battery by (drain-per-metre ?r) per metre. Chargers recharge it.
; Gates open, close and lock: hallways (hall) and pyrobosim locations (fixture).
(define (domain robosim)
  (:requirements :strips :typing :durative-actions :numeric-fluents)
  (:types
    bot item - thing
    area spawn door - spot
    hall fixture - gate)
  (:predicates
    (At ?x - thing ?s - spot)
    (Holding ?r - bot ?o - item)
    (HandEmpty ?r - bot)
    (IsOpen ?g - gate)
    (IsLocked ?g - gate)
    (Has ?l - fixture ?o - item)
    (Searched ?s - spawn)
    (bot-ready ?r - bot)
    (same-room ?a ?b - spot)
    (hall-ends ?a ?b - door ?h - hall)
    (spawn-of ?s - spawn ?l - fixture)
    (reaches-gate ?s - spot ?g - gate)
    (is-charger ?l - fixture))
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
                    (at start (same-room ?from ?to))
                    (at start (>= (battery-level ?r) (* (drain-per-metre ?r) (metres ?from ?to)))))
    :effect (and (at start (not (bot-ready ?r)))
                 (at start (not (At ?r ?from)))
                 (at end (At ?r ?to))
                 (at end (bot-ready ?r))
                 (at end (decrease (battery-level ?r) (* (drain-per-metre ?r) (metres ?from ?to))))))

  (:durative-action cross
    :parameters (?r - bot ?from ?to - door ?h - hall)
    :duration (= ?duration (/ (metres ?from ?to) (top-speed ?r)))
    :condition (and (at start (bot-ready ?r))
                    (at start (At ?r ?from))
                    (at start (hall-ends ?from ?to ?h))
                    (over all (IsOpen ?h))
                    (at start (>= (battery-level ?r) (* (drain-per-metre ?r) (metres ?from ?to)))))
    :effect (and (at start (not (bot-ready ?r)))
                 (at start (not (At ?r ?from)))
                 (at end (At ?r ?to))
                 (at end (bot-ready ?r))
                 (at end (decrease (battery-level ?r) (* (drain-per-metre ?r) (metres ?from ?to))))))

  (:durative-action pick
    :parameters (?r - bot ?o - item ?s - spawn ?l - fixture)
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
    :parameters (?r - bot ?o - item ?s - spawn ?l - fixture)
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
    :parameters (?r - bot ?s - spawn ?l - fixture)
    :duration (= ?duration 1)
    :condition (and (at start (bot-ready ?r))
                    (over all (At ?r ?s))
                    (at start (spawn-of ?s ?l))
                    (over all (IsOpen ?l))
                    (at start (> (battery-level ?r) 0)))
    :effect (and (at start (not (bot-ready ?r)))
                 (at end (Searched ?s))
                 (at end (bot-ready ?r))))

  (:durative-action charge
    :parameters (?r - bot ?s - spawn ?l - fixture)
    :duration (= ?duration 10)
    :condition (and (at start (bot-ready ?r))
                    (over all (At ?r ?s))
                    (at start (spawn-of ?s ?l))
                    (at start (is-charger ?l)))
    :effect (and (at start (not (bot-ready ?r)))
                 (at end (assign (battery-level ?r) 100))
                 (at end (bot-ready ?r)))))
