;; verdict: error
;; message: oneof
;; where: problem
;; line: 15
(define (problem deliver-one)
  (:domain courier)
  (:objects
    van - robot
    depot shop - place
    box - parcel)
  (:init
    (at van depot)
    (lies box depot)
    (empty van)
    (oneof (link depot shop) (link shop depot))
    (link shop depot))
  (:goal (and (lies box shop))))
