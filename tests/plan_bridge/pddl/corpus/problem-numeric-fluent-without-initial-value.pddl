;; verdict: valid
;; unless-installed: kairos tamer enhsp
;; pair: battery-domain.pddl
;; warning: battery(r1) has no initial value
;; warning-line: 9
(define (problem patrol)
  (:domain courier)
  (:objects r1 r2 - robot dock hall - place)
  (:init
    (at r1 dock) (at r2 dock) (link dock hall)
    (= (battery r2) 5))
  (:goal (at r2 hall)))
