; One parcel from the mail room to the lab; the robot starts without a pose.
(define (problem one-parcel)
  (:domain ros-courier)
  (:objects
    courier - robot
    mailroom hall lab office - place
    parcel-1 - parcel)
  (:init
    (at courier mailroom) (lost courier) (empty-handed courier)
    (road mailroom hall) (road hall mailroom)
    (road hall lab) (road lab hall)
    (road hall office) (road office hall)
    (parcel-at parcel-1 mailroom) (addressed-to parcel-1 lab))
  (:goal (delivered parcel-1)))
