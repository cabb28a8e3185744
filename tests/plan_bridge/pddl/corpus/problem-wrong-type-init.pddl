;; verdict: error
;; message: van has type 'robot', but ?c of lies needs type 'parcel'
;; where: problem
;; line: 13
(define (problem deliver-one)
  (:domain courier)
  (:objects
    van - robot
    depot shop - place
    box - parcel)
  (:init
    (at van depot)
    (lies van depot)
    (empty van)
    (link depot shop)
    (link shop depot))
  (:goal (and (lies box shop))))
