; Two people, two drinks, six places: the robot makes two trips to the fridge.
(define (problem fetch-two-drinks)
  (:domain fetch-drink)
  (:objects pr2 - robot
            living-room hallway dining-room kitchen study bedroom - place
            kitchen-fridge - fridge
            top-shelf middle-shelf bottom-shelf - shelf
            cola juice - drink
            alice bob - person)
  (:init (at pr2 hallway) (hand-empty pr2)
         (connected living-room hallway) (connected hallway living-room)
         (connected hallway kitchen) (connected kitchen hallway)
         (connected living-room dining-room) (connected dining-room living-room)
         (connected dining-room kitchen) (connected kitchen dining-room)
         (connected hallway study) (connected study hallway)
         (connected hallway bedroom) (connected bedroom hallway)
         (connected study bedroom) (connected bedroom study)
         (clear living-room hallway) (clear hallway living-room)
         (clear hallway kitchen) (clear kitchen hallway)
         (clear living-room dining-room) (clear dining-room living-room)
         (clear dining-room kitchen) (clear kitchen dining-room)
         (clear hallway study) (clear study hallway)
         (clear hallway bedroom) (clear bedroom hallway)
         (clear study bedroom) (clear bedroom study)
         (fridge-in kitchen-fridge kitchen) (fridge-closed kitchen-fridge)
         (shelf-of top-shelf kitchen-fridge) (shelf-of middle-shelf kitchen-fridge) (shelf-of bottom-shelf kitchen-fridge)
         (on cola middle-shelf) (on juice bottom-shelf)
         (person-at alice living-room) (person-at bob study))
  (:goal (and (served alice cola) (served bob juice) (fridge-closed kitchen-fridge))))
