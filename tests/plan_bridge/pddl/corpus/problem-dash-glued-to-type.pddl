;; verdict: valid
;; plan: 3
;; `-robot` is `- robot`, as in some IPC files.
(define (problem deliver-one)
  (:domain courier)
  (:objects
    van -robot
    depot shop -place
    box -parcel)
  (:init
    (at van depot)
    (lies box depot)
    (empty van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies box shop))))
