;; verdict: error
;; message: this problem is for domain 'curier'
;; where: problem
;; line: 6
(define (problem deliver-one)
  (:domain curier)
  (:objects
    van - robot
    depot shop - place
    box - parcel)
  (:init
    (at van depot)
    (lies box depot)
    (empty van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies box shop))))
