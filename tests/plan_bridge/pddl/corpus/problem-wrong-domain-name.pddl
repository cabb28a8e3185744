;; verdict: valid
;; warning: this problem is for domain 'curier', but the domain file defines 'courier'
;; warning-line: 6
;; plan: 3
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
