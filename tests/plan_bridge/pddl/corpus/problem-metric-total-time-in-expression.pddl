;; verdict: error
;; message: total-time (the makespan inside a metric expression) is not supported
;; pair: durative-domain.pddl
;; where: problem
;; line: 10
(define (problem deliver-one) (:domain courier)
  (:objects van - robot depot shop - place)
  (:init (at van depot) (link depot shop))
  (:goal (at van shop))
  (:metric minimize (+ (* 2 (total-time)) 1)))
