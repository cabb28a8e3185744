;; verdict: error
;; message: variable ?v in (:init ...): initial facts are ground
;; where: problem
;; line: 12
(define (problem deliver-one)
  (:domain courier)
  (:objects
    van - robot
    depot shop - place
    box - parcel)
  (:init
    (at ?v depot)
    (lies box depot)
    (empty van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies box shop))))
