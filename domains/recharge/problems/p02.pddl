; Three deliveries across an office floor; the charger is in the copy room.
(define (problem office-deliveries)
  (:domain recharge)
  (:objects pr2 - robot
            office-a office-b hallway lab kitchen copy-room meeting-room - room
            mail coffee printout - item)
  (:init (at pr2 lab) (hand-empty pr2) (battery-ok pr2) (unplugged pr2)
         (charger-at copy-room)
         (connected office-a hallway) (connected hallway office-a)
         (connected office-b hallway) (connected hallway office-b)
         (connected hallway lab) (connected lab hallway)
         (connected hallway kitchen) (connected kitchen hallway)
         (connected hallway copy-room) (connected copy-room hallway)
         (connected kitchen meeting-room) (connected meeting-room kitchen)
         (connected lab meeting-room) (connected meeting-room lab)
         (connected copy-room office-b) (connected office-b copy-room)
         (item-at mail office-a) (item-at coffee kitchen) (item-at printout copy-room))
  (:goal (and (item-at mail lab) (item-at coffee meeting-room) (item-at printout office-a))))
