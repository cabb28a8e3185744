; From the lab to the office: two doors out of the lab, two doors into the office,
; and an open passage between the west and east halls.
(define (problem lab-to-office)
  (:domain door-opening)
  (:objects pr2 - robot
            lab west-hall east-hall office - room
            lab-west-door lab-east-door office-west-door office-east-door - door)
  (:init (at pr2 lab)
         (door-between lab-west-door lab west-hall) (door-between lab-west-door west-hall lab)
         (door-between lab-east-door lab east-hall) (door-between lab-east-door east-hall lab)
         (door-between office-west-door west-hall office) (door-between office-west-door office west-hall)
         (door-between office-east-door east-hall office) (door-between office-east-door office east-hall)
         (passage west-hall east-hall) (passage east-hall west-hall)
         (door-closed lab-west-door) (door-closed lab-east-door)
         (door-closed office-west-door) (door-closed office-east-door)
         (unlocked lab-west-door) (unlocked lab-east-door)
         (unlocked office-west-door) (unlocked office-east-door))
  (:goal (and (at pr2 office))))
