;; verdict: valid
;; unless-installed: tamer kairos
;; pair: durative-domain.pddl
;; PDDL 2.1's makespan, in upper case: no function declares it.
(define (problem deliver-one) (:domain courier)
  (:objects van - robot depot shop - place)
  (:init (at van depot) (link depot shop))
  (:goal (at van shop))
  (:metric minimize (TOTAL-TIME)))
